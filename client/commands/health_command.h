// `tactforce health`: the grpc.health.v1 serving status of tactforce-server.
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "connection.h"

namespace tactforce::cli {

struct HealthArgs {
  ConnectionArgs connection;  // --server, --tls-*, --deadline-ms
  std::string service;        // "" = the server as a whole
  double wait_s = 0;          // keep asking until SERVING, up to this long
  OutputFormat output;        // json: {"service": ..., "status": ...}
};

CLI::App* AddHealthCommand(CLI::App& app, HealthArgs& args);
int RunHealth(const HealthArgs& args);

}  // namespace tactforce::cli
