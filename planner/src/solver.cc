// ForceSolver::Solve(), the part every backend shares (validation,
// preparation, timing, reported quantities), SolvePrepared (a backend on a
// workspace prepared already), and MakeSolver()/Plan().
#include "tactforce/planner/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "planner/src/backends.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/planner/parameter_uncertainty.h"
#include "tactforce/planner/validation.h"

namespace tactforce::planner {
namespace {

// Smallest slack (N) of the tightened rows and, for ConeModel::kExact, of the
// robust exact cones at the stacked forces f; 0 when there is nothing to meet.
// Each row touches one contact's three coordinates.
double MinMargin(const PreparedProblem& prepared, const PlanOptions& options,
                 const std::vector<Vec3>& forces) {
  static_assert(sizeof(Vec3) == 3 * sizeof(double), "the forces are read as 3n stacked doubles");
  double margin = MinRowSlack(prepared.rows, forces.front().data());
  if (options.cone == ConeModel::kExact) {
    for (int i = 0; i < prepared.num_contacts(); ++i) {
      const Contact& c = prepared.problem.contacts[i];
      margin =
          std::min(margin, ExactConeSlack(c.normal, c.friction, prepared.cone_shift[i], forces[i]));
    }
  }
  return std::isfinite(margin) ? margin : 0.0;
}

// The same minimum from a filled row-margin report (every row and, for
// ConeModel::kExact, every cone; FillRowMargins).
double MinSlack(const std::vector<RowMargin>& margins) {
  double margin = std::numeric_limits<double>::infinity();
  for (const RowMargin& m : margins) margin = std::min(margin, m.slack);
  return std::isfinite(margin) ? margin : 0.0;
}

// A margin of round-off size (an active row's slack, e.g. -2.8e-17 N) is
// reported as exactly 0 so no output reads like a violation: below
// kMarginRoundOff times the largest force (at least 1 N) no backend resolves it.
double SnapRoundOff(double margin, const std::vector<Vec3>& forces) {
  double scale = 1.0;
  for (const Vec3& f : forces) scale = std::max(scale, f.lpNorm<Eigen::Infinity>());
  return std::abs(margin) <= kMarginRoundOff * scale ? 0.0 : margin;
}

int64_t MicrosSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() -
                                                               start)
      .count();
}

void ResetResult(PlanResult* result) {
  result->row_margins.clear();
  result->infeasible_source = UncertaintySource::kNone;
  result->status = PlanStatus::kSolverFailure;
  result->message.clear();
  result->forces.clear();
  result->normal_forces.clear();
  result->objective = 0.0;
  result->min_margin = 0.0;
  result->iterations = 0;
  result->cross_check.reset();
  result->ipopt.runs = 0;
  result->ipopt.status = 0;
  result->ipopt.status_name.clear();
  result->geometric.active_set.clear();
}

void Fail(const char* message, PlanResult* result) {
  result->status = PlanStatus::kSolverFailure;
  result->message = message;
}

// No forces, no derived quantities (a non-OPTIMAL answer).
void ClearAnswer(PlanResult* result) {
  result->forces.clear();
  result->normal_forces.clear();
  result->objective = 0.0;
  result->min_margin = 0.0;
}

// Fills the quantities every backend reports the same way.
void FinishResult(const PreparedProblem& prepared, const PlanOptions& options, PlanResult* result) {
  const PlanProblem& problem = prepared.problem;
  const int n = prepared.num_contacts();
  result->normal_force_sigma = prepared.normal_sigma;
  if (result->status != PlanStatus::kOptimal || static_cast<int>(result->forces.size()) != n) {
    if (result->status == PlanStatus::kOptimal) Fail("backend returned no forces", result);
    ClearAnswer(result);
    if (!prepared.nominal_friction.empty() || prepared.parameters.active) {
      FillRowMargins(prepared, {}, &result->row_margins);
    }
    return;
  }
  result->normal_forces.resize(n);
  result->objective = 0.0;
  for (int i = 0; i < n; ++i) {
    result->normal_forces[i] = problem.contacts[i].normal.dot(result->forces[i]);
    result->objective += result->forces[i].squaredNorm();
  }
  double margin = 0.0;
  if (!prepared.nominal_friction.empty() || prepared.parameters.active) {
    // The report holds every slack MinMargin would compute, by the same
    // expressions: take the minimum from it rather than computing them twice.
    FillRowMargins(prepared, result->forces, &result->row_margins);
    margin = MinSlack(result->row_margins);
  } else {
    margin = MinMargin(prepared, options, result->forces);
  }
  result->min_margin = SnapRoundOff(margin, result->forces);
  // Never an OPTIMAL answer that is not a number: overflow anywhere in a
  // backend becomes a named failure instead of a silent wrong answer.
  if (!std::isfinite(result->objective) || !std::isfinite(result->min_margin)) {
    Fail("the backend's answer is not finite (numerical overflow); scale the problem down", result);
    ClearAnswer(result);
  }
}

}  // namespace

absl::Status ForceSolver::Solve(const PlanProblem& problem, const PlanOptions& options,
                                PlanningWorkspace* workspace, PlanResult* result,
                                const SolveControl& control) const {
  const auto start = std::chrono::steady_clock::now();
  TF_RETURN_IF_ERROR(ValidateProblem(problem, options, &workspace->prepared.problem));
  TF_RETURN_IF_ERROR(SolveValidated(options, control, start, workspace, result));
  if (result->status == PlanStatus::kInfeasible && HasModelUncertainty(problem)) {
    AttributeInfeasibility(problem, options, control, result);
  }
  return absl::OkStatus();
}

absl::Status ForceSolver::Solve(const ValidatedPlan& plan, PlanningWorkspace* workspace,
                                PlanResult* result, const SolveControl& control) const {
  const auto start = std::chrono::steady_clock::now();
  if (!plan.validated()) {
    return absl::InvalidArgumentError("plan: not validated (make it with planner::ValidatePlan)");
  }
  workspace->prepared.problem = plan.problem();  // element-wise: keeps capacity
  TF_RETURN_IF_ERROR(SolveValidated(plan.options(), control, start, workspace, result));
  if (result->status == PlanStatus::kInfeasible && HasModelUncertainty(plan.problem())) {
    AttributeInfeasibility(plan.problem(), plan.options(), control, result);
  }
  return absl::OkStatus();
}

absl::Status ForceSolver::SolveValidated(const PlanOptions& options, const SolveControl& control,
                                         std::chrono::steady_clock::time_point start,
                                         PlanningWorkspace* workspace, PlanResult* result) const {
  TF_RETURN_IF_ERROR(CheckSupported(options));
  PrepareInPlace(options, &workspace->equilibrium_scratch, &workspace->prepared,
                 kind_ == SolverKind::kGeometric);
  SolveAndFinish(options, control, workspace, result);
  result->solve_time_us = MicrosSince(start);
  return absl::OkStatus();
}

void ForceSolver::SolveAndFinish(const PlanOptions& options, const SolveControl& control,
                                 PlanningWorkspace* workspace, PlanResult* result) const {
  ResetResult(result);
  DoSolve(options, control, workspace, result);
  result->solver = kind_;
  FinishResult(workspace->prepared, options, result);
}

void ForceSolver::SolvePrepared(const ForceSolver& backend, const PlanOptions& options,
                                const SolveControl& control, PlanningWorkspace* workspace,
                                PlanResult* result) {
  const auto start = std::chrono::steady_clock::now();
  backend.SolveAndFinish(options, control, workspace, result);
  result->solve_time_us = MicrosSince(start);
  const PlanProblem& prepared = workspace->prepared.problem;
  if (result->status == PlanStatus::kInfeasible && HasModelUncertainty(prepared)) {
    backend.AttributeInfeasibility(prepared, options, control, result);
  }
}

absl::StatusOr<PlanResult> ForceSolver::Solve(const PlanProblem& problem,
                                              const PlanOptions& options,
                                              const SolveControl& control) const {
  PlanningWorkspace workspace;
  PlanResult result;
  TF_RETURN_IF_ERROR(Solve(problem, options, &workspace, &result, control));
  return result;
}

std::unique_ptr<ForceSolver> MakeSolver(SolverKind kind) {
  switch (kind) {
    case SolverKind::kGeometric:
      return internal::MakeGeometricSolver();
    case SolverKind::kIpopt:
      return internal::MakeIpoptSolver();
    case SolverKind::kCrossCheck:
      return internal::MakeCrossCheckSolver();
  }
  return internal::MakeGeometricSolver();
}

const ForceSolver& CachedSolver(SolverKind kind) {
  static const auto* geometric = MakeSolver(SolverKind::kGeometric).release();
  static const auto* ipopt = MakeSolver(SolverKind::kIpopt).release();
  static const auto* cross_check = MakeSolver(SolverKind::kCrossCheck).release();
  switch (kind) {
    case SolverKind::kGeometric:
      return *geometric;
    case SolverKind::kIpopt:
      return *ipopt;
    case SolverKind::kCrossCheck:
      return *cross_check;
  }
  return *geometric;
}

absl::StatusOr<PlanResult> Plan(const PlanProblem& problem, const PlanOptions& options,
                                SolverKind kind, const SolveControl& control) {
  return CachedSolver(kind).Solve(problem, options, control);
}

absl::Status Plan(const PlanProblem& problem, const PlanOptions& options, SolverKind kind,
                  PlanningWorkspace* workspace, PlanResult* result, const SolveControl& control) {
  return CachedSolver(kind).Solve(problem, options, workspace, result, control);
}

}  // namespace tactforce::planner
