// `tactforce demo`: the built-in grasps, geometric planner vs Ipopt.
#pragma once

#include <string>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct DemoArgs {
  std::string format = "table";  // table | json
  int repeat = 3;                // solves per grasp; the fastest times count
};

CLI::App* AddDemoCommand(CLI::App& app, DemoArgs& args);
int RunDemo(const DemoArgs& args);

}  // namespace tactforce::cli
