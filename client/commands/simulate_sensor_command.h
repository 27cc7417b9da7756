// `tactforce simulate sensor`: a simulated fingertip run against a
// reference force (run.csv, fingertip.csv, model.json).
#pragma once

#include <cstdint>
#include <string>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct SimulateSensorArgs {
  std::string model_path;  // model JSON; empty = ideal sensor
  std::string profile = "press-release";
  double seconds = 20.0;
  double rate = 200.0;
  uint64_t seed = 1;
  std::string out_dir;
  bool force = false;  // replace an earlier run's files in out_dir
};
CLI::App* AddSimulateSensorCommand(CLI::App& simulate, SimulateSensorArgs& args);
int RunSimulateSensor(const SimulateSensorArgs& args);

}  // namespace tactforce::cli
