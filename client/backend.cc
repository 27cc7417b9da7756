// The --local / --server ADDR flags of every command that makes an RPC, and
// the backend they choose.
#include "backend.h"

namespace tactforce::cli {

CLI::Option* AddBackendFlags(CLI::App* cmd, BackendArgs* args, const std::string& what,
                             int default_deadline_ms) {
  CLI::Option* local = cmd->add_flag("--local", args->local, "Run in this process (the default)");
  CLI::Option* server = AddConnectionFlags(cmd, &args->connection, "--server", default_deadline_ms);
  // No default address shown: without --server nothing is sent anywhere.
  server->description("Run on tactforce-server at ADDR (" + what + ") instead of in this process")
      ->default_str("");
  server->each([args](const std::string&) { args->remote = true; });
  local->excludes(server);
  return server;
}

absl::StatusOr<std::unique_ptr<Backend>> MakeBackend(const BackendArgs& args) {
  if (!args.remote) return MakeLocalBackend();
  return MakeRemoteBackend(args.connection);
}

}  // namespace tactforce::cli
