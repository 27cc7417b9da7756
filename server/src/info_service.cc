// tactforce.v1.Info (info_service.h): the answer is api::ServerInfo's.
#include "tactforce/server/info_service.h"

#include "tactforce/api/dispatch.h"
#include "tactforce/api/info.h"
#include "tactforce/server/rpc_support.h"

namespace tactforce::server {

grpc::ServerUnaryReactor* InfoService::GetServerInfo(grpc::CallbackServerContext* context,
                                                     const v1::ServerInfoRequest* request,
                                                     v1::ServerInfoResponse* response) {
  const RpcGuard guard(context);
  *response = api::ServerInfo(host_->service_names());
  api::CallLog("GetServerInfo", guard).Emit(absl::OkStatus());
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(grpc::Status::OK);
  return reactor;
}

}  // namespace tactforce::server
