// tactforce.v1.Info (info.proto): GetServerInfo answers the server's version
// and build type (api::ServerInfo, from the generated tactforce/api/version.h)
// and the names of the services its ServerHost serves. Cheap: answered
// inline on the gRPC thread, one log line per call at info.
#pragma once

#include <string>

#include <grpcpp/grpcpp.h>

#include "tactforce/server/server_host.h"
#include "tactforce/v1/info.grpc.pb.h"

namespace tactforce::server {

class InfoService final : public v1::Info::CallbackService, public HostedService {
 public:
  // `host` must outlive the service; its services are read at each call
  // (they are all added before Start, so they no longer change).
  explicit InfoService(const ServerHost* host) : host_(host) {}

  std::string service_name() const override { return std::string(v1::Info::service_full_name()); }
  grpc::Service* grpc_service() override { return this; }

  grpc::ServerUnaryReactor* GetServerInfo(grpc::CallbackServerContext* context,
                                          const v1::ServerInfoRequest* request,
                                          v1::ServerInfoResponse* response) override;

 private:
  const ServerHost* host_;
};

}  // namespace tactforce::server
