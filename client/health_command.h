// `tactforce health`: the grpc.health.v1 serving status of tactforce-server.
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "absl/status/statusor.h"
#include "connection.h"
#include "remote_call.h"

namespace tactforce::cli {

struct HealthArgs {
  ConnectionArgs connection;  // --server, --tls-*, --deadline-ms
  std::string service;        // "" = the server as a whole
  double wait_s = 0;          // keep asking until SERVING, up to this long
  OutputFormat output;        // json: {"service": ..., "status": ...}
};

CLI::App* AddHealthCommand(CLI::App& app, HealthArgs& args);
int RunHealth(const HealthArgs& args);

// One grpc.health.v1.Health/Check of `service`: "SERVING", "NOT_SERVING",
// "UNKNOWN", or "SERVICE_UNKNOWN" when the server does not know the service
// (NOT_FOUND). Other failures as CallUnary reports them (remote_call.h).
absl::StatusOr<std::string> CheckHealth(const RemoteServer& server, const std::string& service);

// InvalidArgument "TARGET does not know service 'NAME' (--service)".
absl::Status UnknownServiceError(const std::string& target, const std::string& service);

}  // namespace tactforce::cli
