// `tactforce audit` and `tactforce simulate sensor`: thin over the audit and
// sensor-simulation libraries.
#pragma once

#include <string>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct AuditArgs {
  std::string csv;             // t,reference,reading[,shear][,trial]
  std::string reference_path;  // two-stream mode: t,value[,shear]
  std::string reading_path;    //                  t,value
  double clock_offset = 0.0;   // s, reading clock minus reference clock
  std::string model_path;      // a given model JSON instead of the affine nominal
  std::string out_dir;
  std::string units = "reading units";
  double heldout_fraction = 0.35;
  int max_causes = 3;
  bool quiet = false;
};
CLI::App* AddAuditCommand(CLI::App& app, AuditArgs& args);
int RunAuditCommand(const AuditArgs& args);

struct SimulateSensorArgs {
  std::string model_path;  // model JSON; empty = ideal sensor
  std::string profile = "press-release";
  double seconds = 20.0;
  double rate = 200.0;
  uint64_t seed = 1;
  std::string out_dir;
};
CLI::App* AddSimulateSensorCommand(CLI::App& simulate, SimulateSensorArgs& args);
int RunSimulateSensor(const SimulateSensorArgs& args);

}  // namespace tactforce::cli
