// ServerHost (server_host.h): credentials from PEM files, the builder with
// message limits, health and reflection, and the drain on shutdown.
#include "tactforce/server/server_host.h"
#include "tactforce/io/status_macros.h"

#include <algorithm>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <utility>
#include <vector>

#include <grpcpp/ext/proto_server_reflection_plugin.h>
#include <grpcpp/health_check_service_interface.h>
#include <grpcpp/impl/server_builder_option.h>
#include <grpcpp/impl/server_builder_plugin.h>
#include <grpcpp/security/server_credentials.h>
#include <grpcpp/support/server_interceptor.h>
#include <google/protobuf/descriptor.h>

#include "absl/container/flat_hash_map.h"
#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "spdlog/spdlog.h"

namespace tactforce::server {
namespace {

absl::StatusOr<std::string> ReadPem(const std::string& path, const char* flag) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::InvalidArgumentError(absl::StrCat(flag, ": cannot read ", path));
  std::stringstream text;
  text << in.rdbuf();
  if (text.str().find("-----BEGIN ") == std::string::npos)
    return absl::InvalidArgumentError(absl::StrCat(flag, ": ", path, " is not PEM"));
  return text.str();
}

absl::StatusOr<std::shared_ptr<grpc::ServerCredentials>> MakeCredentials(const TlsFiles& tls) {
  if (tls.cert.empty() && tls.key.empty() && tls.client_ca.empty())
    return grpc::InsecureServerCredentials();
  if (tls.cert.empty() || tls.key.empty())
    return absl::InvalidArgumentError("--tls-cert and --tls-key must be given together");

  TF_ASSIGN_OR_RETURN(std::string cert, ReadPem(tls.cert, "--tls-cert"));
  TF_ASSIGN_OR_RETURN(std::string key, ReadPem(tls.key, "--tls-key"));

  grpc::SslServerCredentialsOptions ssl;
  ssl.pem_key_cert_pairs.push_back({key, cert});
  if (tls.client_ca.empty()) {
    ssl.client_certificate_request = GRPC_SSL_DONT_REQUEST_CLIENT_CERTIFICATE;
  } else {
    TF_ASSIGN_OR_RETURN(ssl.pem_root_certs, ReadPem(tls.client_ca, "--tls-client-ca"));
    // Mutual TLS: a client without a certificate signed by this CA fails the
    // handshake and never reaches a service.
    ssl.client_certificate_request = GRPC_SSL_REQUEST_AND_REQUIRE_CLIENT_CERTIFICATE_AND_VERIFY;
  }
  return grpc::SslServerCredentials(ssl);
}

// Server reflection on or off for one builder. libgrpc++_reflection
// registers its plugin for every builder of the process when it is loaded,
// so "off" must remove it; "on" keeps exactly one.
class ReflectionOption final : public grpc::ServerBuilderOption {
 public:
  explicit ReflectionOption(bool on) : on_(on) {}
  void UpdateArguments(grpc::ChannelArguments*) override {}
  void UpdatePlugins(std::vector<std::unique_ptr<grpc::ServerBuilderPlugin>>* plugins) override {
    grpc::reflection::ProtoServerReflectionPlugin reflection;
    const std::string name = reflection.name();
    plugins->erase(std::remove_if(plugins->begin(), plugins->end(),
                                  [&name](const auto& plugin) { return plugin->name() == name; }),
                   plugins->end());
    if (on_) plugins->push_back(std::make_unique<grpc::reflection::ProtoServerReflectionPlugin>());
  }

 private:
  bool on_;
};

// A unary request gRPC cannot parse never reaches its handler: the
// callback API answers UNIMPLEMENTED with an empty message, which reads as
// "no such method". This rewrites exactly that answer, on the unary methods
// of the hosted services, to INVALID_ARGUMENT "request cannot be parsed as
// <type>". (No handler of ours answers UNIMPLEMENTED.)
class UnparsedRequestInterceptor final : public grpc::experimental::Interceptor {
 public:
  explicit UnparsedRequestInterceptor(const std::string* message) : message_(message) {}
  void Intercept(grpc::experimental::InterceptorBatchMethods* methods) override {
    if (methods->QueryInterceptionHookPoint(
            grpc::experimental::InterceptionHookPoints::PRE_SEND_STATUS)) {
      const grpc::Status status = methods->GetSendStatus();
      if (status.error_code() == grpc::StatusCode::UNIMPLEMENTED &&
          status.error_message().empty()) {
        methods->ModifySendStatus(grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, *message_));
      }
    }
    methods->Proceed();
  }

 private:
  const std::string* message_;
};

class UnparsedRequestInterceptorFactory final
    : public grpc::experimental::ServerInterceptorFactoryInterface {
 public:
  // `services`: fully-qualified names of the hosted services.
  explicit UnparsedRequestInterceptorFactory(const std::vector<std::string>& services) {
    const auto* pool = google::protobuf::DescriptorPool::generated_pool();
    for (const std::string& name : services) {
      const google::protobuf::ServiceDescriptor* service = pool->FindServiceByName(name);
      if (service == nullptr) continue;
      for (int m = 0; m < service->method_count(); ++m) {
        const google::protobuf::MethodDescriptor* method = service->method(m);
        if (method->client_streaming() || method->server_streaming()) continue;
        messages_[absl::StrCat("/", name, "/", method->name())] =
            absl::StrCat("request cannot be parsed as ", method->input_type()->full_name());
      }
    }
  }
  grpc::experimental::Interceptor* CreateServerInterceptor(
      grpc::experimental::ServerRpcInfo* info) override {
    if (info->type() != grpc::experimental::ServerRpcInfo::Type::UNARY) return nullptr;
    const auto it = messages_.find(info->method());
    return it == messages_.end() ? nullptr : new UnparsedRequestInterceptor(&it->second);
  }

 private:
  absl::flat_hash_map<std::string, std::string> messages_;  // method path -> status message
};

}  // namespace

std::string WithBoundPort(const std::string& address, int port) {
  if (address.size() >= 2 && address.compare(address.size() - 2, 2, ":0") == 0 &&
      address.rfind("unix:", 0) != 0) {
    return absl::StrCat(address.substr(0, address.size() - 1), port);
  }
  return address;
}

ServerHost::ServerHost(ServerOptions options) : options_(std::move(options)) {}

ServerHost::~ServerHost() { Shutdown(std::chrono::milliseconds(0)); }

void ServerHost::AddService(std::unique_ptr<HostedService> service) {
  services_.push_back(std::move(service));
}

std::vector<std::string> ServerHost::service_names() const {
  std::vector<std::string> names = {kHealthServiceName};
  if (options_.reflection) names.push_back(kReflectionServiceName);
  for (const auto& service : services_) names.push_back(service->service_name());
  return names;
}

absl::Status ServerHost::Start() {
  if (server_ != nullptr) return absl::FailedPreconditionError("server already started");
  TF_ASSIGN_OR_RETURN(std::shared_ptr<grpc::ServerCredentials> credentials,
                      MakeCredentials(options_.tls));

  // Process-wide switch; must be set before the builder is made.
  static std::once_flag once;
  std::call_once(once, [] { grpc::EnableDefaultHealthCheckService(true); });

  grpc::ServerBuilder builder;
  builder.SetMaxReceiveMessageSize(options_.max_message_bytes);
  builder.SetMaxSendMessageSize(options_.max_message_bytes);
  builder.AddChannelArgument(GRPC_ARG_MAX_CONCURRENT_STREAMS, options_.max_streams_per_connection);
  builder.AddChannelArgument(GRPC_ARG_ALLOW_REUSEPORT, options_.reuse_port ? 1 : 0);
  builder.SetOption(std::make_unique<ReflectionOption>(options_.reflection));
  int selected_port = 0;
  builder.AddListeningPort(options_.listen, credentials, &selected_port);
  std::vector<std::string> hosted;
  for (const auto& service : services_) {
    builder.RegisterService(service->grpc_service());
    hosted.push_back(service->service_name());
  }
  std::vector<std::unique_ptr<grpc::experimental::ServerInterceptorFactoryInterface>> interceptors;
  interceptors.push_back(std::make_unique<UnparsedRequestInterceptorFactory>(hosted));
  builder.experimental().SetInterceptorCreators(std::move(interceptors));

  server_ = builder.BuildAndStart();
  if (server_ == nullptr || selected_port == 0) {
    server_.reset();
    return absl::UnavailableError(absl::StrCat("cannot listen on ", options_.listen));
  }
  bound_port_ = selected_port;
  bound_address_ = WithBoundPort(options_.listen, selected_port);

  if (grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService()) {
    health->SetServingStatus("", true);
    for (const auto& service : services_) health->SetServingStatus(service->service_name(), true);
  }
  return absl::OkStatus();
}

void ServerHost::Shutdown(std::chrono::milliseconds grace) {
  if (server_ == nullptr || shut_down_) return;
  shut_down_ = true;
  // NOT_SERVING for "" and every service, frozen from here on.
  if (grpc::HealthCheckServiceInterface* health = server_->GetHealthCheckService()) {
    health->Shutdown();
  }
  const auto start = std::chrono::steady_clock::now();
  // Stops accepting, waits for in-flight calls until the deadline, then
  // cancels the rest and waits for their reactors to finish. gRPC also waits
  // for clients to acknowledge its GOAWAY: an idle C-core client does so at
  // its next backup poll (GRPC_CLIENT_CHANNEL_BACKUP_POLL_INTERVAL_MS, 5 s by
  // default), so with idle clients connected the drain can take that long
  // (never longer than `grace`).
  server_->Shutdown(std::chrono::system_clock::now() + grace);
  server_->Wait();
  spdlog::info("event=drained elapsed_ms={}", std::chrono::duration_cast<std::chrono::milliseconds>(
                                                  std::chrono::steady_clock::now() - start)
                                                  .count());
}

}  // namespace tactforce::server
