// Force plans along a motion and friction-probe plans (trajectory.h).
#include "tactforce/planner/trajectory.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/validation.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::planner {

Eigen::Matrix3d Inertia::Matrix() const {
  Eigen::Matrix3d m;
  m << ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz;
  return m;
}

Wrench RequiredContactWrench(const ObjectModel& o, const Eigen::Matrix3d& inertia_com,
                             const TrajectoryStep& s) {
  const Vec3& c = o.com;
  const Vec3& w = s.angular_velocity;
  const Vec3& dw = s.angular_acceleration;
  const Vec3 a_minus_g = s.linear_acceleration - s.gravity;
  // Parallel axis: I_o = I_c + m (|c|^2 I - c c^T).
  const Eigen::Matrix3d inertia_origin =
      inertia_com + o.mass * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  Wrench out;
  out.force = o.mass * a_minus_g + o.mass * (dw.cross(c) + w.cross(w.cross(c)));
  out.torque = inertia_origin * dw + w.cross(inertia_origin * w) + o.mass * c.cross(a_minus_g);
  return out;
}

PlanProblem StepProblem(const TrajectoryProblem& t, int step) {
  const TrajectoryStep& s = t.steps[step];
  PlanProblem p = t.base;
  p.object.gravity = s.gravity;
  if (s.contacts.has_value()) p.contacts = *s.contacts;
  const Eigen::Matrix3d inertia = t.inertia ? t.inertia->Matrix() : Eigen::Matrix3d::Zero();
  const Wrench need = RequiredContactWrench(p.object, inertia, s);
  // The planner balances b = -(w_g + w_ext) with w_g = (m g, c x m g); pick
  // w_ext so that b equals the Newton-Euler wrench (plus the base wrench).
  const Vec3 weight = p.object.mass * s.gravity;
  p.external_wrench.force += s.external_wrench.force - need.force - weight;
  p.external_wrench.torque += s.external_wrench.torque - need.torque - p.object.com.cross(weight);
  p.motion = {s.linear_acceleration, s.angular_velocity, s.angular_acceleration};
  return p;
}

namespace {

constexpr double kMaxProbeSteps = 100000;

}  // namespace

absl::StatusOr<TrajectoryResult> PlanTrajectory(const TrajectoryProblem& t,
                                                const PlanOptions& options, SolverKind kind,
                                                bool warm_start, const SolveControl& control) {
  const auto start = std::chrono::steady_clock::now();
  if (t.steps.empty()) return absl::InvalidArgumentError("steps: at least one step is required");
  if (t.inertia) {
    TF_RETURN_IF_ERROR(ValidateInertia(*t.inertia));
  }
  // Every step before any solve: a bad last step must not cost the others.
  for (int i = 0; i < static_cast<int>(t.steps.size()); ++i) {
    TF_RETURN_IF_ERROR(ValidateTrajectoryStep(t.steps[i], i, t.inertia.has_value()));
  }
  const std::unique_ptr<ForceSolver> solver = MakeSolver(kind);
  TrajectoryResult out;
  out.steps.reserve(t.steps.size());
  PlanOptions step_options = options;
  PlanningWorkspace workspace;  // one for the whole motion
  for (int i = 0; i < static_cast<int>(t.steps.size()); ++i) {
    // Deadlines, cancellation and shutdown end a long motion between steps.
    if (control.interrupt && control.interrupt()) {
      return absl::CancelledError(
          absl::StrCat("interrupted after ", i, " of ", t.steps.size(), " steps"));
    }
    PlanResult& r = out.steps.emplace_back();
    if (absl::Status s = solver->Solve(StepProblem(t, i), step_options, &workspace, &r, control);
        !s.ok()) {
      const std::string msg(s.message());
      // Field paths of a step's own contacts are reported under the step.
      const bool own_contacts = t.steps[i].contacts.has_value() && msg.rfind("contacts", 0) == 0;
      return absl::Status(s.code(), own_contacts ? absl::StrCat("steps[", i, "].", msg)
                                                 : absl::StrCat(msg, " (at steps[", i, "])"));
    }
    if (warm_start && r.status == PlanStatus::kOptimal)
      step_options.warm_start = r.geometric.active_set;
    switch (r.status) {
      case PlanStatus::kOptimal:
        ++out.optimal;
        break;
      case PlanStatus::kInfeasible:
        ++out.infeasible;
        break;
      case PlanStatus::kSolverFailure:
        ++out.failed;
        break;
    }
  }
  out.total_time_us = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::steady_clock::now() - start)
                          .count();
  return out;
}

absl::StatusOr<ProbePlan> PlanFrictionProbe(const PlanProblem& holding_grasp,
                                            const FrictionProbe& probe, const PlanOptions& options,
                                            SolverKind kind, const SolveControl& control) {
  Vec3 n, t;
  TF_RETURN_IF_ERROR(ValidateFrictionProbe(probe, &n, &t));
  const double duration = (probe.initial_normal_force - probe.final_normal_force) / probe.ramp_rate;
  // Counted in double first: the product can exceed any int (UB to cast).
  const double step_count = std::floor(duration * probe.sample_rate) + 1;
  if (!(step_count <= kMaxProbeSteps)) {
    return absl::InvalidArgumentError(
        "probe.sample_rate: more than 100000 steps; ramp faster or sample slower");
  }
  const int steps = static_cast<int>(step_count);

  ProbePlan plan;
  TrajectoryProblem trajectory;
  trajectory.base = holding_grasp;
  for (int k = 0; k < steps; ++k) {
    const double time = k / probe.sample_rate;
    const double fn =
        std::max(probe.final_normal_force, probe.initial_normal_force - probe.ramp_rate * time);
    const Vec3 f = fn * n + probe.tangential_force * t;
    plan.times.push_back(time);
    plan.probe_forces.push_back(f);
    TrajectoryStep step;
    step.gravity = holding_grasp.object.gravity;
    step.external_wrench = {f, probe.position.cross(f)};
    trajectory.steps.push_back(step);
  }
  TF_ASSIGN_OR_RETURN(plan.holding, PlanTrajectory(trajectory, options, kind, true, control));
  return plan;
}

}  // namespace tactforce::planner
