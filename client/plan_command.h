// `tactforce plan`: one request (JSON file or stdin) -> one plan, computed by
// tactforce-server (default, --server ADDR) or in this process (--local).
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "connection.h"

namespace tactforce::cli {

struct PlanArgs {
  bool local = false;           // plan in this process
  ConnectionArgs connection;    // --server, --tls-*, --deadline-ms
  std::string request_path;     // "-" = stdin
  std::string trajectory_path;  // TrajectoryRequest JSON instead of --request
  std::string format = "json";  // json | table
};

CLI::App* AddPlanCommand(CLI::App& app, PlanArgs& args);
int RunPlan(const PlanArgs& args);

}  // namespace tactforce::cli
