// `tactforce experiment probe`: friction probed inside a grasp in MuJoCo
// (tactforce::experiment::RunProbeExperiment), a table or JSON.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "cli_common.h"

namespace tactforce::cli {

struct ProbeArgs {
  std::vector<double> mus;     // own surfaces; empty: the built-in surface pairs
  std::string object = "box";  // built-in name or FILE.json
  bool on_table = false;
  int trials = 10;
  uint64_t seed = 1;
  double force_sigma = 0.05;    // N per axis
  double force_bias = 0.02;     // N per axis (std. dev. of the per-trial bias)
  double contact_sigma = 2e-5;  // m per axis
  double hold_scale = 1.0;
  double admittance_gain = 0.05;    // per tick; 0: impedance only
  double plan_sigma = 1.0;          // N, the holding plan's robustness (grip margin)
  std::string pre_slip = "window";  // window (the paper) | fit
  OutputFormat output;
  bool no_progress = false;
  bool details = false;
  CLI::App* app = nullptr;
};

// Adds `probe` under `experiment`.
CLI::App* AddProbeCommand(CLI::App* experiment, ProbeArgs& args);
int RunProbe(const ProbeArgs& args);

}  // namespace tactforce::cli
