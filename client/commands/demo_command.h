// `tactforce demo`: the built-in grasps, geometric planner vs Ipopt, in this
// process; with --server ADDR also through tactforce-server (plans checked
// against the local ones, health, and a short load test).
#pragma once

#include <string>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "connection.h"

namespace tactforce::cli {

struct DemoArgs {
  OutputFormat output;        // table | json
  int repeat = 3;             // solves per grasp; the fastest times count
  std::string server;         // empty: local only
  ConnectionArgs connection;  // --tls-*, --deadline-ms (server taken from `server`)
  double load_seconds = 5.0;  // the load test against --server; 0 = skip
  int load_concurrency = 8;
};

CLI::App* AddDemoCommand(CLI::App& app, DemoArgs& args);
int RunDemo(const DemoArgs& args);

}  // namespace tactforce::cli
