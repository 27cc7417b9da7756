// `tactforce experiment ablation`: the paper's inertia ablation
// (tactforce::experiment::RunAblation): every method on every source,
// medians per cell beside the paper's Tables I-IV, as markdown or JSON.
#pragma once

#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "cli_common.h"

namespace tactforce::cli {

struct AblationArgs {
  int seeds = 3;
  uint64_t first_seed = 1;
  double duration = 10, rate = 100;
  std::vector<std::string> sources;  // empty: all
  std::vector<std::string> methods;  // empty: all
  bool no_progress = false;
  OutputFormat output;
  CLI::App* cmd = nullptr;
};

// Adds `ablation` under `experiment`.
void AddAblationSubcommand(CLI::App* experiment, AblationArgs& args);
int RunAblationCommand(const AblationArgs& args);

}  // namespace tactforce::cli
