// CROSS_CHECK backend: the geometric answer, compared with the Ipopt reference.
#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "planner/src/backends.h"

namespace tactforce::planner::internal {
namespace {

class CrossCheckSolver final : public ForceSolver {
 public:
  CrossCheckSolver()
      : ForceSolver(SolverKind::kCrossCheck),
        geometric_(MakeGeometricSolver()),
        ipopt_(MakeIpoptSolver()) {}

 protected:
  absl::Status CheckSupported(const PlanOptions& options) const override {
    if (options.cone == ConeModel::kExact) {
      return absl::InvalidArgumentError(
          "cone: CONE_MODEL_EXACT cannot be cross-checked: the geometric backend plans with "
          "the pyramidal cone; use SOLVER_IPOPT");
    }
    return absl::OkStatus();
  }

  void DoSolve(const PlanOptions& options, PlanningWorkspace* workspace,
               PlanResult* out) const override {
    *out = Compare(workspace->prepared, options);
  }

 private:
  PlanResult Compare(const PreparedProblem& prepared, const PlanOptions& options) const {
    absl::StatusOr<PlanResult> geometric = geometric_->Solve(prepared.problem, options);
    absl::StatusOr<PlanResult> ipopt = ipopt_->Solve(prepared.problem, options);
    if (!geometric.ok() || !ipopt.ok()) {  // cannot happen after validation
      PlanResult failed;
      failed.status = PlanStatus::kSolverFailure;
      failed.message = std::string((!geometric.ok() ? geometric.status() : ipopt.status()).message());
      return failed;
    }
    PlanResult result = *geometric;
    CrossCheckReport report;
    report.geometric_time_us = geometric->solve_time_us;
    report.ipopt_time_us = ipopt->solve_time_us;
    report.ipopt_status = ipopt->status;
    report.ipopt_message = ipopt->message;
    const bool same_status = geometric->status == ipopt->status;
    if (same_status && geometric->status == PlanStatus::kOptimal) {
      for (size_t i = 0; i < geometric->forces.size(); ++i) {
        report.max_force_diff = std::max(
            report.max_force_diff, (geometric->forces[i] - ipopt->forces[i]).cwiseAbs().maxCoeff());
      }
      report.objective_rel_diff = std::abs(geometric->objective - ipopt->objective) /
                                  std::max(1.0, std::abs(ipopt->objective));
    }
    report.agree = same_status && report.max_force_diff <= options.agreement_tolerance;
    if (!same_status) {
      absl::StrAppend(&result.message, result.message.empty() ? "" : "; ",
                      "cross-check: Ipopt says ", ToString(ipopt->status),
                      ipopt->message.empty() ? "" : absl::StrCat(" (", ipopt->message, ")"));
    }
    result.iterations = geometric->iterations;
    result.cross_check = report;
    return result;
  }

  std::unique_ptr<ForceSolver> geometric_;
  std::unique_ptr<ForceSolver> ipopt_;
};

}  // namespace

std::unique_ptr<ForceSolver> MakeCrossCheckSolver() { return std::make_unique<CrossCheckSolver>(); }

}  // namespace tactforce::planner::internal
