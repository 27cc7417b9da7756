// ForceSolver::Solve(), the part every backend shares (validation,
// preparation, timing, reported quantities), and MakeSolver()/Plan().
#include "tactforce/planner/solver.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "planner/src/backends.h"
#include "tactforce/planner/validation.h"

namespace tactforce::planner {
namespace {

// Smallest slack (N) of the tightened rows and, for ConeModel::kExact, of the
// robust exact cones at the stacked forces f; 0 when there is nothing to meet.
double MinMargin(const PreparedProblem& prepared, const PlanOptions& options,
                 const std::vector<Vec3>& forces, const Eigen::VectorXd& stacked) {
  double margin = std::numeric_limits<double>::infinity();
  if (prepared.rows.matrix.rows() > 0) {
    margin = (prepared.rows.rhs - prepared.rows.matrix * stacked).minCoeff();
  }
  if (options.cone == ConeModel::kExact) {
    for (int i = 0; i < prepared.num_contacts(); ++i) {
      const Contact& c = prepared.problem.contacts[i];
      margin = std::min(margin,
                        ExactConeSlack(c.normal, c.friction, prepared.cone_shift[i], forces[i]));
    }
  }
  return std::isfinite(margin) ? margin : 0.0;
}

// Fills the quantities every backend reports the same way.
void FinishResult(const PreparedProblem& prepared, const PlanOptions& options,
                  PlanResult* result) {
  const PlanProblem& problem = prepared.problem;
  const int n = prepared.num_contacts();
  result->normal_force_sigma = prepared.normal_sigma;
  if (result->status != PlanStatus::kOptimal || static_cast<int>(result->forces.size()) != n) {
    if (result->status == PlanStatus::kOptimal) {
      result->status = PlanStatus::kSolverFailure;
      result->message = "backend returned no forces";
    }
    result->forces.clear();
    result->normal_forces.clear();
    result->objective = 0.0;
    result->min_margin = 0.0;
    return;
  }
  Eigen::VectorXd stacked(3 * n);
  result->normal_forces.resize(n);
  result->objective = 0.0;
  for (int i = 0; i < n; ++i) {
    stacked.segment<3>(3 * i) = result->forces[i];
    result->normal_forces[i] = problem.contacts[i].normal.dot(result->forces[i]);
    result->objective += result->forces[i].squaredNorm();
  }
  result->min_margin = MinMargin(prepared, options, result->forces, stacked);
}

}  // namespace

absl::StatusOr<PlanResult> ForceSolver::Solve(const PlanProblem& problem,
                                              const PlanOptions& options) const {
  const auto start = std::chrono::steady_clock::now();
  absl::StatusOr<PlanProblem> validated = ValidateProblem(problem, options);
  if (!validated.ok()) return validated.status();
  if (absl::Status supported = CheckSupported(options); !supported.ok()) return supported;

  const PreparedProblem prepared = Prepare(*std::move(validated), options);
  PlanResult result = DoSolve(prepared, options);
  result.solver = kind_;
  FinishResult(prepared, options, &result);
  result.solve_time_us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::steady_clock::now() - start)
                             .count();
  return result;
}

std::unique_ptr<ForceSolver> MakeSolver(SolverKind kind) {
  switch (kind) {
    case SolverKind::kGeometric: return internal::MakeGeometricSolver();
    case SolverKind::kIpopt: return internal::MakeIpoptSolver();
    case SolverKind::kCrossCheck: return internal::MakeCrossCheckSolver();
  }
  return internal::MakeGeometricSolver();
}

absl::StatusOr<PlanResult> Plan(const PlanProblem& problem, const PlanOptions& options,
                                SolverKind kind) {
  static const auto* geometric = MakeSolver(SolverKind::kGeometric).release();
  static const auto* ipopt = MakeSolver(SolverKind::kIpopt).release();
  static const auto* cross_check = MakeSolver(SolverKind::kCrossCheck).release();
  switch (kind) {
    case SolverKind::kGeometric: return geometric->Solve(problem, options);
    case SolverKind::kIpopt: return ipopt->Solve(problem, options);
    case SolverKind::kCrossCheck: return cross_check->Solve(problem, options);
  }
  return geometric->Solve(problem, options);
}

}  // namespace tactforce::planner
