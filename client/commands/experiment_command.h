// `tactforce experiment grasp|slope`: closed-loop grasp experiments and the
// slope-method friction ground truth in MuJoCo (tactforce::experiment).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "experiment_ablation_command.h"
#include "experiment_chain_command.h"
#include "experiment_inhand_command.h"
#include "experiment_probe_command.h"

namespace tactforce::cli {

struct ExperimentArgs {
  // grasp
  std::string object = "all";  // sphere|wrench|cylinder|cube|all
  int trials = 20;
  std::string feedback = "both";  // estimated|raw|both
  uint64_t seed = 1;
  OutputFormat output;  // --json / --format json
  std::string plots_dir;
  std::string estimator = "normal-lsq";  // normal-lsq|projection
  std::string admittance = "full";       // full|normal
  std::string sensor_model_path;         // one model JSON for every fingertip
  bool ideal = false;                    // ideal sensors
  bool no_progress = false;
  bool details = false;                   // one line per trial
  std::string sensors = "channel";        // channel|taxel
  std::string protocol = "short";         // short|paper
  std::string taxel_ranges_path;          // --taxel-ranges FILE (sim::TaxelRanges JSON)
  std::optional<double> contact_cap_deg;  // --contact-cap DEG (default: GraspConfig's)
  double normal_uncertainty_deg = -1;     // --normal-uncertainty DEG (GraspConfig)
  std::string contact_sensing = "mean";   // --contact-sensing (GraspConfig::contact_sensing)
  // slope
  std::vector<double> mus = {0.3, 0.5, 0.7, 0.9};
  double tilt_rate = 0.5;  // deg/s
  bool creep = true;

  CLI::App* grasp = nullptr;
  CLI::App* slope = nullptr;
  InHandArgs inhand;      // `experiment inhand`
  AblationArgs ablation;  // `experiment ablation`
  ProbeArgs probe;        // `experiment probe` (experiment_probe_command.h)
  ChainArgs chain;        // `experiment chain` (experiment_chain_command.h)
};
CLI::App* AddExperimentCommand(CLI::App& app, ExperimentArgs& args);
int RunExperiment(const ExperimentArgs& args);

}  // namespace tactforce::cli
