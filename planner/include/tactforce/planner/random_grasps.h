// Seeded random grasps for property tests, benchmarks and load generation:
// contacts on spheres, boxes and cylinders (normals into the object), CoM
// inside the object, random object orientation (gravity direction).
#pragma once

#include <cstdint>
#include <random>

#include "tactforce/planner/types.h"

namespace tactforce::planner {

struct RandomGraspOptions {
  int min_contacts = 2;
  int max_contacts = 6;
  double min_friction = 0.2, max_friction = 1.2;
  double max_sigma = 0.5;                  // N
  double max_min_force = 1.0;              // N
  double min_mass = 0.05, max_mass = 2.0;  // kg
  double extrinsic_probability = 0.15;
  // Fraction of grasps made infeasible on purpose: frictionless contacts
  // that all push horizontally, or an antipodal pair twisted about its axis.
  double infeasible_fraction = 0.1;
};

struct RandomGrasp {
  PlanProblem problem;
  bool infeasible_by_construction = false;
};

RandomGrasp MakeRandomGrasp(std::mt19937_64& rng, const RandomGraspOptions& options = {});

}  // namespace tactforce::planner
