// Fixtures shared by the Ipopt backend's tests (ipopt_solver_test.cc and
// the internal formulation/NLP tests): sphere grasps in the object frame,
// SI units, and their PreparedProblem.
#pragma once

#include <cmath>
#include <numbers>

#include <gtest/gtest.h>

#include "tactforce/planner/force_model.h"
#include "tactforce/planner/types.h"
#include "tactforce/planner/validation.h"

namespace tactforce::planner::fixtures {

inline Contact Finger(const Vec3& position, const Vec3& normal, double mu, double min_force = 0.0,
                      double sigma = 0.0) {
  Contact c;
  c.position = position;
  c.normal = normal;
  c.friction = mu;
  c.min_normal_force = min_force;
  c.sigma = sigma;
  return c;
}

// Antipodal pinch of a sphere of radius 3 cm: contacts at (+-r, 0, 0) with
// normals (-+1, 0, 0), gravity along -z.
inline PlanProblem Pinch(double mass, double mu, double min_force = 0.0) {
  const double r = 0.03;
  PlanProblem p;
  p.object.mass = mass;
  p.contacts.push_back(Finger(Vec3(r, 0, 0), Vec3(-1, 0, 0), mu, min_force));
  p.contacts.push_back(Finger(Vec3(-r, 0, 0), Vec3(1, 0, 0), mu, min_force));
  return p;
}

// Three fingers 120 degrees apart, slightly below the equator of a sphere,
// plus a fourth on top: a 3-4 contact grasp with a non-trivial optimum.
inline PlanProblem ThreeFingerGrasp(int contacts = 3, double sigma = 0.0) {
  const double r = 0.04;
  PlanProblem p;
  p.object.mass = 0.3;
  p.object.com = Vec3(0.004, -0.002, 0.003);
  const double mus[] = {0.6, 0.8, 0.5};
  for (int i = 0; i < 3; ++i) {
    const double a = 2.0 * std::numbers::pi * i / 3.0 + 0.2;
    const Vec3 d = Vec3(std::cos(a), std::sin(a), -0.3).normalized();
    p.contacts.push_back(Finger(r * d, -d, mus[i], i == 1 ? 0.5 : 0.0, sigma));
  }
  if (contacts > 3) {
    const Vec3 d = Vec3(0.1, 0.0, 1.0).normalized();
    p.contacts.push_back(Finger(r * d, -d, 0.4, 0.2, sigma));
  }
  return p;
}

inline PlanOptions Options(ConeModel cone, double kappa = 0.0, int sides = 12) {
  PlanOptions o;
  o.cone = cone;
  o.confidence = kappa;
  o.cone_sides = sides;
  return o;
}

// Validate + Prepare, as ForceSolver::Solve does; the problem must be valid.
inline PreparedProblem Prepared(const PlanProblem& problem, const PlanOptions& options) {
  absl::StatusOr<PlanProblem> validated = ValidateProblem(problem, options);
  EXPECT_TRUE(validated.ok()) << validated.status();
  return Prepare(validated.ok() ? *validated : problem, options);
}

}  // namespace tactforce::planner::fixtures
