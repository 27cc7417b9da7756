// Built-in example grasps (the demo's embedded default and test fixtures),
// modelled on the GeoDEx experiments.
#pragma once

#include <string>
#include <vector>

#include "tactforce/planner/trajectory.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner {

struct ExampleGrasp {
  std::string name;         // "sphere-pinch", "wrench-3f", "cylinder-4f"
  std::string description;  // one line for people
  PlanProblem problem;
  PlanOptions options;
};

// 2-finger pinch of a 0.082 kg sphere; 3-finger wrench grasp, 0.3 kg,
// mu 0.9, sigma 0.5 N; 4-finger grasp of a 0.36 kg cylinder, diameter 0.11 m.
std::vector<ExampleGrasp> BuiltInGrasps();

// The wrench grasp lifted (vertical acceleration 0.5 sin(2 pi s / T)) and
// rotated 0.6 rad about its handle axis with a smooth cosine profile over
// T = 2 s, sampled at `steps` steps (GeoDEx Table II's motion).
TrajectoryProblem WrenchLiftAndRotate(int steps);

}  // namespace tactforce::planner
