#include "tactforce/planner/trajectory.h"

#include <cmath>

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include "tactforce/planner/examples.h"

namespace tactforce::planner {
namespace {

TrajectoryProblem LiftAndRotate(int steps) { return WrenchLiftAndRotate(steps); }

TEST(Trajectory, EveryStepSatisfiesNewtonEuler) {
  const TrajectoryProblem t = LiftAndRotate(50);
  for (SolverKind kind : {SolverKind::kGeometric, SolverKind::kIpopt}) {
    absl::StatusOr<TrajectoryResult> r = PlanTrajectory(t, PlanOptions{}, kind);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_EQ(r->optimal, 50) << ToString(kind);
    const ObjectModel& o = t.base.object;
    const Eigen::Matrix3d ic = t.inertia->Matrix();
    const Eigen::Matrix3d io = ic + o.mass * (o.com.squaredNorm() * Eigen::Matrix3d::Identity() -
                                              o.com * o.com.transpose());
    for (size_t k = 0; k < t.steps.size(); ++k) {
      const TrajectoryStep& s = t.steps[k];
      Vec3 force = Vec3::Zero(), torque = Vec3::Zero();
      for (size_t i = 0; i < r->steps[k].forces.size(); ++i) {
        force += r->steps[k].forces[i];
        torque += t.base.contacts[i].position.cross(r->steps[k].forces[i]);
      }
      const Vec3& w = s.angular_velocity;
      const Vec3& dw = s.angular_acceleration;
      const Vec3 a_g = s.linear_acceleration - s.gravity;
      const Vec3 want_f = o.mass * a_g + o.mass * (dw.cross(o.com) + w.cross(w.cross(o.com)));
      const Vec3 want_t = io * dw + w.cross(io * w) + o.mass * o.com.cross(a_g);
      const double tol = kind == SolverKind::kGeometric ? 1e-8 : 1e-7;
      EXPECT_LE((force - want_f).norm(), tol) << "step " << k;
      EXPECT_LE((torque - want_t).norm(), tol) << "step " << k;
    }
  }
}

TEST(Trajectory, WarmStartChangesNothingButWork) {
  const TrajectoryProblem t = LiftAndRotate(100);
  absl::StatusOr<TrajectoryResult> warm =
      PlanTrajectory(t, PlanOptions{}, SolverKind::kGeometric, true);
  absl::StatusOr<TrajectoryResult> cold =
      PlanTrajectory(t, PlanOptions{}, SolverKind::kGeometric, false);
  ASSERT_TRUE(warm.ok() && cold.ok());
  int warm_iters = 0, cold_iters = 0;
  for (int k = 0; k < 100; ++k) {
    for (int i = 0; i < 3; ++i) {
      EXPECT_LE((warm->steps[k].forces[i] - cold->steps[k].forces[i]).norm(), 1e-9);
    }
    warm_iters += warm->steps[k].iterations;
    cold_iters += cold->steps[k].iterations;
  }
  // Cold solves that enter the farthest violated row often need no drop at
  // all (one step per active row, the least possible): the warm start then
  // saves scans, not steps.
  EXPECT_LE(warm_iters, cold_iters);
}

TEST(Trajectory, ErrorsNameTheStep) {
  TrajectoryProblem t = LiftAndRotate(5);
  TrajectoryProblem no_inertia = t;
  no_inertia.inertia.reset();
  EXPECT_NE(PlanTrajectory(no_inertia, PlanOptions{}, SolverKind::kGeometric)
                .status()
                .message()
                .find("object.inertia: required because steps[0]"),
            std::string::npos);
  t.steps[3].angular_velocity.x() = NAN;
  EXPECT_EQ(PlanTrajectory(t, PlanOptions{}, SolverKind::kGeometric).status().message(),
            "steps[3].angular_velocity: not a finite vector");
  t = LiftAndRotate(5);
  t.steps[2].contacts = t.base.contacts;
  (*t.steps[2].contacts)[1].normal.setZero();
  EXPECT_EQ(PlanTrajectory(t, PlanOptions{}, SolverKind::kGeometric).status().message(),
            "steps[2].contacts[1].normal: zero length");
  t.steps.clear();
  EXPECT_FALSE(PlanTrajectory(t, PlanOptions{}, SolverKind::kGeometric).ok());
}

}  // namespace
}  // namespace tactforce::planner

namespace tactforce::planner {
namespace {

TEST(FrictionProbe, HoldingFingersBalanceTheProbe) {
  PlanProblem hold;
  for (const auto& g : BuiltInGrasps()) {
    if (g.name == "cylinder-4f") hold = g.problem;
  }
  FrictionProbe probe;
  probe.position = Vec3(0, 0, 0.06);  // on the top face
  probe.normal = Vec3(0, 0, -1);
  probe.tangent = Vec3(1, 0, 0.3);  // projected onto the face
  probe.tangential_force = 1.0;
  probe.initial_normal_force = 3.0;
  probe.final_normal_force = 0.5;
  probe.ramp_rate = 1.0;
  probe.sample_rate = 20.0;
  absl::StatusOr<ProbePlan> plan =
      PlanFrictionProbe(hold, probe, PlanOptions{}, SolverKind::kGeometric);
  ASSERT_TRUE(plan.ok()) << plan.status();
  ASSERT_EQ(plan->times.size(), 51u);
  EXPECT_EQ(plan->holding.optimal, 51);
  for (size_t k = 0; k < plan->times.size(); ++k) {
    const Vec3& fp = plan->probe_forces[k];
    EXPECT_NEAR(fp.z(), -std::max(0.5, 3.0 - plan->times[k]), 1e-12);
    EXPECT_NEAR(Vec3(fp.x(), fp.y(), 0).norm(), 1.0, 1e-12);
    // Holding forces + probe + weight balance.
    Vec3 force = fp + hold.object.mass * hold.object.gravity;
    Vec3 torque = probe.position.cross(fp);
    for (size_t i = 0; i < hold.contacts.size(); ++i) {
      force += plan->holding.steps[k].forces[i];
      torque += hold.contacts[i].position.cross(plan->holding.steps[k].forces[i]);
    }
    EXPECT_LE(force.norm(), 1e-8);
    EXPECT_LE(torque.norm(), 1e-8);
  }
  probe.tangent = probe.normal;
  EXPECT_EQ(
      PlanFrictionProbe(hold, probe, PlanOptions{}, SolverKind::kGeometric).status().message(),
      "probe.tangent: zero length after projection onto the tangent plane");
  // Issue 16: 2.5e18 steps were cast to int (undefined behaviour) and
  // answered "at least one step is required".
  probe.tangent = Vec3(1, 0, 0);
  probe.ramp_rate = 1e-9;
  probe.sample_rate = 1e9;
  EXPECT_EQ(
      PlanFrictionProbe(hold, probe, PlanOptions{}, SolverKind::kGeometric).status().message(),
      "probe.sample_rate: more than 100000 steps; ramp faster or sample slower");
}

// Issue 16: deadlines, cancellation and shutdown reach a long motion between
// its steps (only Ipopt polled the interrupt before).
TEST(Trajectory, InterruptEndsTheMotionBetweenSteps) {
  const TrajectoryProblem t = LiftAndRotate(200);
  int polls = 0;
  PlanOptions o;
  const SolveControl control{[&polls] { return ++polls > 3; }};
  absl::StatusOr<TrajectoryResult> r = PlanTrajectory(t, o, SolverKind::kGeometric, true, control);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kCancelled);
  EXPECT_EQ(r.status().message(), "interrupted after 3 of 200 steps");
  TrajectoryProblem bad = t;
  bad.inertia->ixx = -1e-4;
  EXPECT_EQ(
      PlanTrajectory(bad, PlanOptions{}, SolverKind::kGeometric).status().message().substr(0, 16),
      "object.inertia: ");
}

}  // namespace
}  // namespace tactforce::planner
