// Force planning along a motion (GeoDEx Problem 4): at every step the
// contacts must supply the Newton-Euler wrench of the moving object
// (Sundaralingam & Hermans eq. 6-7), all in the object frame:
//   sum f     = m (a - g) + m (dw x c + w x (w x c))
//   sum p x f = I_o dw + w x (I_o w) + m c x (a - g)
// with I_o the inertia about the object origin (parallel axis from I_c).
#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner {

// Inertia about the CoM in object axes (kg m^2).
struct Inertia {
  double ixx = 0, iyy = 0, izz = 0, ixy = 0, ixz = 0, iyz = 0;
  Eigen::Matrix3d Matrix() const;
};

struct TrajectoryStep {
  Vec3 gravity = Vec3(0, 0, -9.81);              // in the (rotating) object frame
  Vec3 linear_acceleration = Vec3::Zero();       // a of the object origin (m/s^2)
  Vec3 angular_velocity = Vec3::Zero();          // w (rad/s)
  Vec3 angular_acceleration = Vec3::Zero();      // dw (rad/s^2)
  std::optional<std::vector<Contact>> contacts;  // overrides the base contacts
  Wrench external_wrench;                        // added to the base's external wrench at this step
};

struct TrajectoryProblem {
  PlanProblem base;                // object, contacts, constant external wrench
  std::optional<Inertia> inertia;  // required when any step rotates
  std::vector<TrajectoryStep> steps;
};

struct TrajectoryResult {
  std::vector<PlanResult> steps;
  int optimal = 0, infeasible = 0, failed = 0;
  int64_t total_time_us = 0;
};

// The wrench (force, torque about the origin) the contacts must supply.
Wrench RequiredContactWrench(const ObjectModel& object, const Eigen::Matrix3d& inertia_com,
                             const TrajectoryStep& step);

// The single-step problem whose equilibrium equals the Newton-Euler step.
PlanProblem StepProblem(const TrajectoryProblem& trajectory, int step);

// Plans every step with `kind`. With `warm_start` the geometric backend
// starts each step from the previous step's active set. Errors name the
// field ("steps[3].angular_velocity: ...", "steps[3].contacts[1].normal: ...").
// `control.interrupt` is polled between steps (CancelledError "interrupted
// after i of n steps") and by each step's Ipopt solves.
absl::StatusOr<TrajectoryResult> PlanTrajectory(const TrajectoryProblem& trajectory,
                                                const PlanOptions& options, SolverKind kind,
                                                bool warm_start = true,
                                                const SolveControl& control = {});

// Friction probing (Sundaralingam & Hermans III-A): a probe finger pushes at
// `position` with a constant tangential force along `tangent` while its
// normal force ramps down from `initial_normal_force` at `ramp_rate` until
// `final_normal_force`; the holding grasp must keep the object still.
struct FrictionProbe {
  Vec3 position = Vec3::Zero();
  Vec3 normal = Vec3::UnitZ();        // into the object
  Vec3 tangent = Vec3::UnitX();       // projected onto the tangent plane
  double tangential_force = 1.0;      // N
  double initial_normal_force = 4.0;  // N
  double final_normal_force = 0.0;    // N
  double ramp_rate = 0.5;             // N/s
  double sample_rate = 50.0;          // Hz
};

struct ProbePlan {
  std::vector<double> times;       // s
  std::vector<Vec3> probe_forces;  // N, applied by the probe to the object
  TrajectoryResult holding;        // the holding fingers' plan per step
};

// Errors name the field ("probe.normal: zero length", ...).
absl::StatusOr<ProbePlan> PlanFrictionProbe(const PlanProblem& holding_grasp,
                                            const FrictionProbe& probe, const PlanOptions& options,
                                            SolverKind kind, const SolveControl& control = {});

}  // namespace tactforce::planner
