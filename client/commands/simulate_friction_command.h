// `tactforce simulate friction`: probing trials with their truth.
#pragma once

#include <cstdint>
#include <string>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct SimulateFrictionArgs {
  double mu = 0.5;
  int trials = 10;
  double noise = 0.05;
  double rate = 200.0;
  double ramp = 0.5;
  double tangential_force = 3.0;
  bool slip_flags = false;
  uint64_t seed = 1;
  std::string out_dir;
  bool force = false;  // replace an earlier run's files in out_dir
};
// Adds `friction` under the given `simulate` command.
CLI::App* AddSimulateFrictionCommand(CLI::App& simulate, SimulateFrictionArgs& args);
int RunSimulateFriction(const SimulateFrictionArgs& args);

}  // namespace tactforce::cli
