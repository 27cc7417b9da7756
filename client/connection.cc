// The connection flags, channels with their credentials, and the mapping of
// a failed gRPC call to the CLI's one-line error; --target lists.
#include "connection.h"

#include <array>
#include <cstring>
#include <string_view>

#include <grpcpp/security/credentials.h>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
#include "absl/strings/strip.h"
#include "cli_common.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

absl::StatusOr<std::string> ReadPem(const std::string& path, const char* flag) {
  TF_ASSIGN_OR_RETURN(std::string text, ReadInput(path, flag));
  if (text.find("-----BEGIN ") == std::string::npos) {
    return absl::InvalidArgumentError(absl::StrCat(flag, ": '", path, "' is not a PEM file"));
  }
  return text;
}

}  // namespace

CLI::Option* AddConnectionFlags(CLI::App* cmd, ConnectionArgs* args, const std::string& server_flag,
                                int default_deadline_ms) {
  args->deadline_ms = default_deadline_ms;
  CLI::Option* server = nullptr;
  if (!server_flag.empty()) {
    server = cmd->add_option(server_flag, args->server,
                             "tactforce-server address: HOST:PORT or a gRPC target URI")
                 ->type_name("ADDR")
                 ->capture_default_str();
  }
  cmd->add_option("--tls-ca", args->tls_ca,
                  "Use TLS; trust server certificates signed by this PEM CA bundle "
                  "(default with other --tls-* flags: the system roots)")
      ->type_name("FILE")
      ->check(CLI::ExistingFile.description(""));
  CLI::Option* cert =
      cmd->add_option("--tls-cert", args->tls_cert,
                      "Use mutual TLS: PEM client certificate chain (needs --tls-key)")
          ->type_name("FILE")
          ->check(CLI::ExistingFile.description(""));
  CLI::Option* key = cmd->add_option("--tls-key", args->tls_key, "PEM private key of --tls-cert")
                         ->type_name("FILE")
                         ->check(CLI::ExistingFile.description(""));
  cert->needs(key);
  key->needs(cert);
  cmd->add_option("--tls-server-name", args->tls_server_name,
                  "Use TLS; expect this name in the server certificate instead of the "
                  "host of the address")
      ->type_name("NAME");
  cmd->add_option("--deadline-ms", args->deadline_ms,
                  "Deadline of each call in milliseconds (0 = none)")
      ->check(CLI::Range(0, 86'400'000))
      ->capture_default_str();
  return server;
}

absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(const ConnectionArgs& args,
                                                           const std::string& target,
                                                           grpc::ChannelArguments channel_args) {
  if (target.empty()) return absl::InvalidArgumentError("--server: empty address");
  std::shared_ptr<grpc::ChannelCredentials> credentials;
  if (!args.tls()) {
    credentials = grpc::InsecureChannelCredentials();
  } else {
    grpc::SslCredentialsOptions ssl;
    if (!args.tls_ca.empty()) {
      TF_ASSIGN_OR_RETURN(ssl.pem_root_certs, ReadPem(args.tls_ca, "--tls-ca"));
    }
    if (!args.tls_cert.empty() || !args.tls_key.empty()) {
      if (args.tls_cert.empty() || args.tls_key.empty()) {
        return absl::InvalidArgumentError("--tls-cert and --tls-key must be given together");
      }
      TF_ASSIGN_OR_RETURN(std::string cert, ReadPem(args.tls_cert, "--tls-cert"));
      TF_ASSIGN_OR_RETURN(std::string key, ReadPem(args.tls_key, "--tls-key"));
      ssl.pem_cert_chain = std::move(cert);
      ssl.pem_private_key = std::move(key);
    }
    credentials = grpc::SslCredentials(ssl);
    if (!args.tls_server_name.empty()) {
      channel_args.SetSslTargetNameOverride(args.tls_server_name);
    }
  }
  std::shared_ptr<grpc::Channel> channel =
      grpc::CreateCustomChannel(target, credentials, channel_args);
  if (channel == nullptr) {
    return absl::InvalidArgumentError(absl::StrCat("--server: cannot use '", target, "'"));
  }
  return channel;
}

void SetDeadline(grpc::ClientContext* context, int deadline_ms) {
  if (deadline_ms > 0) {
    context->set_deadline(std::chrono::system_clock::now() +
                          std::chrono::milliseconds(deadline_ms));
  }
}

absl::Status RpcError(const grpc::Status& status, const std::string& target, int deadline_ms,
                      grpc::Channel* channel) {
  const std::string& message = status.error_message();
  switch (status.error_code()) {
    case grpc::StatusCode::OK:
      return absl::OkStatus();
    case grpc::StatusCode::UNAVAILABLE:
      return absl::UnavailableError(absl::StrCat("cannot reach ", target, ": ", message));
    case grpc::StatusCode::DEADLINE_EXCEEDED:
      if (channel != nullptr && channel->GetState(false) != GRPC_CHANNEL_READY) {
        return absl::UnavailableError(absl::StrCat("cannot reach ", target,
                                                   ": no connection within ", deadline_ms,
                                                   " ms (--deadline-ms)"));
      }
      return absl::DeadlineExceededError(
          absl::StrCat(target, ": no answer within ", deadline_ms, " ms (--deadline-ms)"));
    case grpc::StatusCode::INVALID_ARGUMENT:
      return absl::InvalidArgumentError(message);
    default:
      // absl and gRPC share the canonical code numbers.
      return absl::Status(static_cast<absl::StatusCode>(status.error_code()),
                          absl::StrCat(target, ": ", message));
  }
}

std::string StatusCodeName(grpc::StatusCode code) {
  // absl and gRPC share the canonical codes and their names.
  std::string name = absl::StatusCodeToString(static_cast<absl::StatusCode>(code));
  if (name.empty()) return absl::StrCat("CODE_", static_cast<int>(code));
  return name;
}

bool HasUriScheme(const std::string& target) {
  static constexpr std::array<std::string_view, 7> kSchemes = {
      "ipv4:", "ipv6:", "dns:", "unix:", "unix-abstract:", "vsock:", "xds:"};
  for (std::string_view scheme : kSchemes) {
    if (target.compare(0, scheme.size(), scheme) == 0) return true;
  }
  return false;
}

absl::StatusOr<std::vector<std::string>> SplitTargets(const std::string& value) {
  if (HasUriScheme(value)) return std::vector<std::string>{value};
  std::vector<std::string> targets;
  for (absl::string_view part : absl::StrSplit(value, ',')) {
    part = absl::StripAsciiWhitespace(part);
    if (part.empty()) {
      return absl::InvalidArgumentError(absl::StrCat("--target: empty address in '", value, "'"));
    }
    targets.emplace_back(part);
  }
  return targets;
}

}  // namespace tactforce::cli
