// Helpers shared by the inertia tests.
#pragma once

#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>

#include "tactforce/inertia/simulate.h"

namespace tactforce::inertia::testing {

// $TACTFORCE_SOURCE_DIR/../shared/data/inertia, or nullopt when absent.
inline std::optional<std::string> SharedInertiaDir() {
  const char* src = std::getenv("TACTFORCE_SOURCE_DIR");
  const std::string dir = std::string(src ? src : ".") + "/../shared/data/inertia";
  if (FILE* f = std::fopen((dir + "/Hammer.csv").c_str(), "r")) {
    std::fclose(f);
    return dir;
  }
  return std::nullopt;
}

// A short, fast simulation (3 s at 100 Hz) of a built-in object.
inline SimulationOptions ShortSimulation(const std::string& object, SimulationMode mode,
                                         bool kinematics) {
  SimulationOptions o;
  o.object = object;
  o.mode = mode;
  o.duration = 3.0;
  o.rate_hz = 100.0;
  o.write_kinematics = kinematics;
  o.seed = 7;
  return o;
}

}  // namespace tactforce::inertia::testing
