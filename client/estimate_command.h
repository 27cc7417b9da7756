// `tactforce estimate`, `tactforce friction`, `tactforce simulate friction`.
#pragma once

#include <string>
#include <vector>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "connection.h"

namespace tactforce::cli {

struct EstimateArgs {
  bool local = false;
  ConnectionArgs connection;  // --server, TLS, --deadline-ms
  std::string request_path;   // EstimateRequest JSON, "-" = stdin
  OutputFormat output;
};
CLI::App* AddEstimateCommand(CLI::App& app, EstimateArgs& args);
int RunEstimate(const EstimateArgs& args);

struct FrictionArgs {
  std::vector<std::string> trial_paths;  // CSV: t,fx,fy,fz,px,py,pz[,slip]
  std::string normal;                    // "x,y,z"
  std::string mesh_path;                 // STL or OBJ
  OutputFormat output;
  bool linear_fit = false;
  double slip_distance = 1e-3;
  int window = 5;
  double min_normal_force = 0.05;
};
CLI::App* AddFrictionCommand(CLI::App& app, FrictionArgs& args);
int RunFriction(const FrictionArgs& args);

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
