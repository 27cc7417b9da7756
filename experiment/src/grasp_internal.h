// Internal (not installed): what GraspSetup::Create prepares once per object
// and RunGraspTrial reads every tick — the phase timeline, the hand's rigid
// motion and the per-tick force plans (GraspSetup::Impl).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "tactforce/experiment/grasp.h"
#include "absl/status/statusor.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/types.h"
#include "tactforce/sim/simulate.h"

namespace tactforce::experiment {

// Minimum-jerk profile s(tau), tau clamped to [0, 1], and its first and
// second derivatives with respect to tau.
void MinJerk(double tau, double* s, double* ds, double* dds);

// Start times (s) of the phases after `close`, and the end of the trial.
struct Timeline {
  double t_settle, t_hold, t_lift, t_hold_lifted, t_place, t_placed, t_switched, t_end;
  bool has_placed = false, has_switched = false;
  explicit Timeline(const PhaseDurations& p);
  Phase At(double t) const;
};

// The hand's rigid motion relative to its pose at rest (identity before the
// lift): x_world = R (x0 - pivot) + pivot + p.
struct HandMotion {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  planner::Vec3 p = planner::Vec3::Zero();   // m
  planner::Vec3 v = planner::Vec3::Zero();   // translation velocity (m/s)
  planner::Vec3 a = planner::Vec3::Zero();   // m/s^2
  planner::Vec3 w = planner::Vec3::Zero();   // angular velocity (world, rad/s)
  planner::Vec3 dw = planner::Vec3::Zero();  // rad/s^2
};

struct GraspSetup::Impl {
  std::vector<std::string> finger_names;
  planner::PlanProblem base;  // object frame, intrinsic contacts first
  planner::Inertia inertia;   // about the CoM (kg m^2)
  // What the plans and the estimator use: `base` and `inertia`, or the
  // config's PlanningModel applied to them (the simulation keeps the truth).
  planner::PlanProblem plan_base;
  planner::Inertia plan_inertia;
  int n_fingers = 0;
  planner::Vec3 rest_origin = planner::Vec3::Zero();  // object origin (world) at rest
  bool pivot = false;                                 // cube: rotate about `pivot_point` around +x
  planner::Vec3 pivot_point = planner::Vec3::Zero();  // world
  double amplitude = 0;                               // m (lift) or rad (pivot)
  PhaseDurations phases;
  Timeline timeline{PhaseDurations{}};
  int ticks = 0;
  std::vector<planner::PlanProblem> tick_problem;      // per control tick (estimation)
  std::vector<std::vector<double>> tick_desired;       // per tick, per finger (N)
  std::vector<std::vector<planner::Vec3>> tick_force;  // per tick, per finger, object frame (N)
  planner::PlanOptions plan_options;  // what the ticks were planned with (re-plans use them too)
  sim::FingertipGeometry fingertip;   // the config's fingertip radius, the default body
  // sin of the sensed normal's trusted error (GraspConfig::normal_uncertainty_deg
  // resolved once per set-up: taxels without a value take the dome's resolution).
  double sin_normal_uncertainty = 0;

  // The hand's motion at time t (lift, hold, place; or the pivot).
  HandMotion Motion(double t) const;
  // Where the hand moves a world point that was at x0 at rest, its velocity
  // and its acceleration.
  planner::Vec3 Apply(const HandMotion& h, const planner::Vec3& x0) const;
  planner::Vec3 Velocity(const HandMotion& h, const planner::Vec3& x0) const;
  planner::Vec3 Acceleration(const HandMotion& h, const planner::Vec3& x0) const;
};

// Per-tick plans for ticks [first, ticks) of `im`'s motion with `contacts`
// (object frame) in place of the grasp's: desired normal forces, forces and
// the estimation problems, index 0 = tick `first`. Errors: the planner's.
struct TickPlans {
  std::vector<std::vector<double>> desired;
  std::vector<std::vector<planner::Vec3>> force;
  std::vector<planner::PlanProblem> problem;
};
absl::StatusOr<TickPlans> PlanTickRange(const GraspConfig& config, const GraspSetup::Impl& im,
                                        const std::vector<planner::Contact>& contacts, int first);

// Labels a failed trial's cause (FailureCause in grasp.h) from what the
// fingertips read and truly felt every control tick until the failure.
class CauseTracker {
 public:
  explicit CauseTracker(int n_fingers);
  // One control tick (settle onward, until the first failure criterion is met).
  void Tick(double t, const std::vector<double>& truth, const std::vector<double>& reading);
  FailureCause Label(bool failed, bool tilted) const;

 private:
  struct Finger {
    double low_since = -1, low_truth = 0;  // run of reading < 50 % of truth
    double off_since = -1;                 // run of truth < 0.1 N after touching
    bool touched = false;
    double over_sum = 0;
  };
  std::vector<Finger> fingers_;
  long ticks_ = 0;
  bool non_activation_ = false, phantom_ = false;
};

}  // namespace tactforce::experiment
