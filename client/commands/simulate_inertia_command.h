// `tactforce simulate inertia`: write a simulated inertia log (inertia.csv),
// its truth (truth.json) and the object's solid (mesh.stl) for `tactforce
// inertia` to fit.
#pragma once

#include <cstdint>
#include <string>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct SimulateInertiaArgs {
  std::string object = "seed-table1";
  std::string params_path;       // custom object: truth JSON format
  std::string mode = "in-hand";  // in-hand | wrist
  int contacts = 4;
  double seconds = 10.0;
  double rate = 100.0;
  double force_variance = 0.0;  // N^2 (the paper's noise unit)
  double torque_sigma = 0.0;
  double position_sigma = 0.0;
  double orientation_sigma = 0.0;
  std::string noise_level;       // Nadeau et al.: low | moderate | high (wrist mode)
  bool kinematics = false;       // write measured kinematics columns
  double amplitude_scale = 1.0;  // scales the default excitation amplitudes
  double frequency_scale = 1.0;  // scales its frequencies
  std::string trajectory_path;   // JSON excitation trajectory instead of the default
  uint64_t seed = 1;
  std::string out_dir;  // writes inertia.csv, truth.json and mesh.stl
  bool force = false;   // replace an earlier run's files in out_dir
};
CLI::App* AddSimulateInertiaCommand(CLI::App& simulate, SimulateInertiaArgs& args);
int RunSimulateInertia(const SimulateInertiaArgs& args);

}  // namespace tactforce::cli
