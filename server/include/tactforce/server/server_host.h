// The process-level gRPC server: one listening port, optional (mutual) TLS,
// message size limits, the standard health service (grpc.health.v1) and
// server reflection, hosting any number of services.
//
// Adding a service (Estimator, Audit, ...) is one line in main.cc:
//
//   ServerHost host(options);
//   host.AddService(std::make_unique<PlannerService>(&pool, planner_options));
//   host.AddService(std::make_unique<EstimatorService>(...));
//   host.AddService(std::make_unique<InfoService>(&host));  // lists them all
//   absl::Status s = host.Start();   // health: SERVING for "" and each name
//   ...
//   host.Shutdown(grace);            // NOT_SERVING, drain, cancel the rest
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/status/status.h"

namespace tactforce::server {

// A gRPC service the host registers and reports in the health service.
class HostedService {
 public:
  virtual ~HostedService() = default;
  // Fully-qualified name, e.g. "tactforce.v1.Planner" (health service key).
  virtual std::string service_name() const = 0;
  // The implementation to register; owned by this object.
  virtual grpc::Service* grpc_service() = 0;
};

struct TlsFiles {
  std::string cert;       // PEM certificate chain; empty = plaintext
  std::string key;        // PEM private key
  std::string client_ca;  // PEM CA bundle: require + verify client certs
};

struct ServerOptions {
  std::string listen = "127.0.0.1:50051";
  int max_message_bytes = 4 << 20;  // receive and send
  TlsFiles tls;
  // Calls in flight per client connection (HTTP/2 SETTINGS_MAX_CONCURRENT_STREAMS).
  int max_streams_per_connection = 128;
  bool reflection = true;  // serve grpc.reflection.v1alpha
  // SO_REUSEPORT: off, so a second server on a port in use fails to start
  // instead of silently taking half of the calls; on only when asked.
  bool reuse_port = false;
};

class ServerHost {
 public:
  explicit ServerHost(ServerOptions options);
  ~ServerHost();  // Shutdown(0) if still running

  ServerHost(const ServerHost&) = delete;
  ServerHost& operator=(const ServerHost&) = delete;

  // Before Start() only.
  void AddService(std::unique_ptr<HostedService> service);

  // Binds and starts serving; health is SERVING when this returns OK.
  // Errors: unreadable TLS files, bind failure.
  absl::Status Start();

  // The listen address with the port actually bound (port 0 resolved).
  const std::string& bound_address() const { return bound_address_; }
  int bound_port() const { return bound_port_; }
  bool tls() const { return !options_.tls.cert.empty(); }

  // Fully-qualified names of every service served: the added ones plus the
  // standard health and (unless turned off) reflection services (what reflection's
  // list_services answers; tests/server/info_rpc_test.cc compares the two).
  std::vector<std::string> service_names() const;

  // Health NOT_SERVING, stop accepting calls, let in-flight calls finish for
  // up to `grace`, then cancel what is left and wait for it. Idempotent.
  void Shutdown(std::chrono::milliseconds grace);

 private:
  ServerOptions options_;
  std::vector<std::unique_ptr<HostedService>> services_;
  std::unique_ptr<grpc::Server> server_;
  std::string bound_address_;
  int bound_port_ = 0;
  bool shut_down_ = false;
};

// The standard services every ServerHost serves besides its own.
inline constexpr char kHealthServiceName[] = "grpc.health.v1.Health";
inline constexpr char kReflectionServiceName[] = "grpc.reflection.v1alpha.ServerReflection";

// Replaces a trailing ":0" port with `port` ("127.0.0.1:0" -> "127.0.0.1:43211",
// "[::1]:0" -> "[::1]:43211"); other addresses are returned unchanged.
std::string WithBoundPort(const std::string& address, int port);

}  // namespace tactforce::server
