// Talking to tactforce-server: the connection flags shared by every remote
// subcommand (--server, --tls-*, --deadline-ms), channel construction, and
// the mapping of gRPC failures to one-line errors with the exit codes of
// cli_common.h.
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "CLI/CLI.hpp"
#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tactforce::cli {

inline constexpr char kDefaultServer[] = "localhost:50051";

struct ConnectionArgs {
  // gRPC target: HOST:PORT, or any gRPC URI (dns:///h:p, ipv4:a:p,b:p, unix:/path).
  std::string server = kDefaultServer;
  // TLS (mirrors the server's --tls-cert/--tls-key/--tls-client-ca). Any of
  // them switches TLS on; without --tls-ca the system roots are trusted.
  std::string tls_ca;           // PEM CA bundle that signed the server's certificate
  std::string tls_cert;         // PEM client certificate chain (mutual TLS)
  std::string tls_key;          // PEM private key of tls_cert
  std::string tls_server_name;  // expected name in the server certificate
  int deadline_ms = 30'000;     // per call; 0 = none

  bool tls() const {
    return !tls_ca.empty() || !tls_cert.empty() || !tls_key.empty() || !tls_server_name.empty();
  }
};

// Adds --server (named `server_flag`, e.g. "--server" or "--server,--target";
// empty: not added, the caller has its own), --tls-ca, --tls-cert,
// --tls-key, --tls-server-name and --deadline-ms to `cmd`. Returns the
// --server option (null when not added).
CLI::Option* AddConnectionFlags(CLI::App* cmd, ConnectionArgs* args,
                                const std::string& server_flag = "--server",
                                int default_deadline_ms = 30'000);

// A channel to `target` with the credentials of `args` (the PEM files are
// read here: InvalidArgument naming the flag when unreadable). `channel_args`
// is extended with the TLS name override when set. Does not connect.
absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(
    const ConnectionArgs& args, const std::string& target,
    grpc::ChannelArguments channel_args = {});

// Sets the deadline of `context` to now + deadline_ms (no-op for 0).
void SetDeadline(grpc::ClientContext* context, int deadline_ms);

// A failed RPC as the error the CLI reports (see cli_common.h):
//   UNAVAILABLE        -> Unavailable("cannot reach TARGET: <gRPC message>")
//   DEADLINE_EXCEEDED  -> DeadlineExceeded("TARGET: no answer within N ms"),
//                         or Unavailable("cannot reach TARGET: no connection
//                         within N ms") when `channel` never got connected
//   INVALID_ARGUMENT   -> InvalidArgument(<server message: field path>)
//   anything else      -> same code, "TARGET: <message>"
// `channel` may be null.
absl::Status RpcError(const grpc::Status& status, const std::string& target, int deadline_ms,
                      grpc::Channel* channel = nullptr);

// "OK", "UNAVAILABLE", ... (gRPC's canonical names).
std::string StatusCodeName(grpc::StatusCode code);

// Splits a --target list. A value with a URI scheme (ipv4:, ipv6:, dns:,
// unix:, ...) is one gRPC target and is returned as is; otherwise it is a
// comma-separated list of HOST:PORT. Empty entries are rejected.
absl::StatusOr<std::vector<std::string>> SplitTargets(const std::string& value);

// True for "ipv4:...", "dns:///...", "unix:..." (a gRPC URI, not HOST:PORT).
bool HasUriScheme(const std::string& target);

}  // namespace tactforce::cli
