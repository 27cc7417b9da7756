// `tactforce experiment inhand`: the in-hand inertia data source in MuJoCo
// (tactforce::experiment::RunInHand): flags to an InHandConfig, the run's
// files (inertia.csv, truth.json, events.csv, truth_log.csv, mesh.obj) and
// optionally every inertia method fitted to it.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "cli_common.h"

namespace tactforce::cli {

struct InHandArgs {
  std::string object = "box_0";  // built-in name or FILE.json
  std::string tracker = "vision";
  double duration = 10, rate = 100;
  uint64_t seed = 1;
  std::string force_model = "biotac";
  bool ideal_forces = false, ideal_tracking = false;
  double support_fraction = 0;
  std::vector<std::string> breaks;  // CONTACT:START:DURATION
  std::string out_dir = "inhand_run";
  bool force = false;  // replace an earlier run's files in --out
  bool fit = false;
  bool no_progress = false;
  OutputFormat output;
  CLI::App* cmd = nullptr;
};

// Adds `inhand` under `experiment`.
void AddInHandSubcommand(CLI::App* experiment, InHandArgs& args);
int RunInHandCommand(const InHandArgs& args);

}  // namespace tactforce::cli
