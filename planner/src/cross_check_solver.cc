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

  // Both backends on the one prepared workspace (validated and prepared
  // once by Solve): the geometric answer into `out`, Ipopt's beside it.
  void DoSolve(const PlanOptions& options, const SolveControl& control,
               PlanningWorkspace* workspace, PlanResult* out) const override {
    SolvePrepared(*geometric_, options, control, workspace, out);
    PlanResult ipopt;
    SolvePrepared(*ipopt_, options, control, workspace, &ipopt);
    Compare(ipopt, options, out);
  }

 private:
  static void Compare(const PlanResult& ipopt, const PlanOptions& options, PlanResult* result) {
    const PlanResult& geometric = *result;
    CrossCheckReport report;
    report.geometric_time_us = geometric.solve_time_us;
    report.ipopt_time_us = ipopt.solve_time_us;
    report.ipopt_status = ipopt.status;
    report.ipopt_message = ipopt.message;
    const bool same_status = geometric.status == ipopt.status;
    if (same_status && geometric.status == PlanStatus::kOptimal) {
      for (size_t i = 0; i < geometric.forces.size(); ++i) {
        report.max_force_diff = std::max(
            report.max_force_diff, (geometric.forces[i] - ipopt.forces[i]).cwiseAbs().maxCoeff());
      }
      report.objective_rel_diff = std::abs(geometric.objective - ipopt.objective) /
                                  std::max(1.0, std::abs(ipopt.objective));
    }
    report.agree = same_status && report.max_force_diff <= options.agreement_tolerance;
    if (!same_status) {
      absl::StrAppend(&result->message, result->message.empty() ? "" : "; ",
                      "cross-check: Ipopt says ", ToString(ipopt.status),
                      ipopt.message.empty() ? "" : absl::StrCat(" (", ipopt.message, ")"));
    }
    result->ipopt = ipopt.ipopt;
    result->cross_check = std::move(report);
  }

  std::unique_ptr<ForceSolver> geometric_;
  std::unique_ptr<ForceSolver> ipopt_;
};

}  // namespace

std::unique_ptr<ForceSolver> MakeCrossCheckSolver() { return std::make_unique<CrossCheckSolver>(); }

}  // namespace tactforce::planner::internal
