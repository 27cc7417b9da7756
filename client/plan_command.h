// `tactforce plan`: one request (JSON file or stdin) -> one plan.
#pragma once

#include <string>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct PlanArgs {
  bool local = false;          // plan in this process
  std::string request_path;    // "-" = stdin
  std::string format = "json";  // json | table
  // Server mode (--server ADDR, default localhost:50051) arrives with the
  // gRPC service; SelectBackend() in plan_command.cc is where it plugs in.
};

CLI::App* AddPlanCommand(CLI::App& app, PlanArgs& args);
int RunPlan(const PlanArgs& args);

}  // namespace tactforce::cli
