// `tactforce experiment chain`: probe -> fit -> plan -> lift in MuJoCo
// (tactforce::experiment::RunChain), a table or JSON
// {"rows": [{"object", "planning", "successes", "trials", "median_squeeze_n",
// "min_slip_margin"}...]}.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "cli_common.h"

namespace tactforce::cli {

struct ChainArgs {
  std::vector<std::string> objects = {"sphere", "wrench", "cylinder"};
  int trials = 5;  // closed-loop trials per object, seed and planning
  int seeds = 2;
  uint64_t seed = 1;
  int probe_trials = 3;
  double inhand_duration = 4;  // s
  double confidence = 1.0;     // kappa_b
  std::string fit_method = "constrained";
  OutputFormat output;
  bool no_progress = false;
  CLI::App* app = nullptr;
};

// Adds `chain` under `experiment`.
CLI::App* AddChainCommand(CLI::App* experiment, ChainArgs& args);
int RunChainCommand(const ChainArgs& args);

}  // namespace tactforce::cli
