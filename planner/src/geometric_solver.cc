// GEOMETRIC backend (GeoDEx fast path): forces on the FE-plane f = f0 + B x.
// Because B is orthonormal and f0 is orthogonal to it, sum |f_i|^2 =
// |f0|^2 + |x|^2, so the plan is the minimum-norm x of a small polytope:
// a dense strictly convex QP in d = dim null(G) variables.
#include <string>

#include "absl/strings/str_cat.h"
#include "planner/src/backends.h"
#include "tactforce/planner/dense_qp.h"
#include "tactforce/planner/workspace.h"

namespace tactforce::planner::internal {
namespace {

std::string DescribeActive(const PreparedProblem& prepared, const std::vector<int>& rows) {
  std::string out;
  const int shown = std::min<int>(static_cast<int>(rows.size()), 4);
  for (int i = 0; i < shown; ++i) {
    absl::StrAppend(&out, i ? "; " : "", prepared.rows.Describe(rows[i], prepared.problem));
  }
  if (static_cast<int>(rows.size()) > shown) absl::StrAppend(&out, "; ...");
  return out;
}

// Below this many FE-plane coordinates a dense row (d numbers) is as cheap
// to scan as the row structure (3 per row plus 3 d per contact).
constexpr int kMinStructuredCoordinates = 3;

// min 0.5 |x|^2 + (B^T f0)^T x  s.t. (A B) x <= d - A f0. From 3
// coordinates on, in the QP's row structure: row r of contact i is its
// direction a_r applied to B_i x (B_i: the contact's three rows of B), so
// A B is never formed.
void FillPlaneQp(const PreparedProblem& prepared, DenseQp* qp) {
  const ForceEquilibrium& eq = prepared.equilibrium;
  const ConstraintRows& rows = prepared.rows;
  const int d = static_cast<int>(eq.null_basis.cols());
  const int m = static_cast<int>(rows.info.size());
  qp->identity_hessian = true;
  qp->hessian.resize(0, 0);
  qp->gradient.noalias() = eq.null_basis.transpose() * eq.particular;  // zero up to round-off
  qp->eq_matrix.resize(0, d);
  qp->eq_rhs.resize(0);
  if (d < kMinStructuredCoordinates) {
    qp->in_directions.resize(0, 3);
    RowsOnPlane(rows, eq, &qp->in_matrix, &qp->in_rhs);
    return;
  }
  qp->in_matrix.resize(0, d);
  qp->in_block_maps = eq.null_basis;
  qp->in_directions = rows.directions;
  qp->in_block_first = rows.contact_first;  // contact i's rows are block i
  qp->in_rhs.resize(m);
  RowSlacks(rows, eq.particular.data(), qp->in_rhs.data());
}

class GeometricSolver final : public ForceSolver {
 public:
  GeometricSolver() : ForceSolver(SolverKind::kGeometric) {}

 protected:
  absl::Status CheckSupported(const PlanOptions& options) const override {
    if (options.cone == ConeModel::kExact) {
      return absl::InvalidArgumentError(
          "cone: CONE_MODEL_EXACT is only solved by SOLVER_IPOPT; the geometric backend "
          "plans with the pyramidal cone (CONE_MODEL_PYRAMID)");
    }
    return absl::OkStatus();
  }

  void DoSolve(const PlanOptions& options, const SolveControl& /*control*/,
               PlanningWorkspace* workspace, PlanResult* result) const override {
    const PreparedProblem& prepared = workspace->prepared;
    const ForceEquilibrium& eq = prepared.equilibrium;
    if (!eq.consistent) {
      result->status = PlanStatus::kInfeasible;
      result->message = absl::StrCat("the contacts cannot resist this wrench: G has rank ", eq.rank,
                                     " and the required wrench leaves a residual of ", eq.residual);
      return;
    }
    FillPlaneQp(prepared, &workspace->qp);
    DenseQpSettings settings;
    settings.warm_start = options.warm_start;
    DenseQpResult& qp_result = workspace->qp_result;
    SolveDenseQp(workspace->qp, settings, &workspace->qp_workspace, &qp_result);
    result->iterations = qp_result.iterations;
    result->geometric.active_set = qp_result.active_set;
    switch (qp_result.status) {
      case DenseQpStatus::kOptimal: {
        result->status = PlanStatus::kOptimal;
        Eigen::VectorXd& f = workspace->forces;
        f = eq.particular;
        f.noalias() += eq.null_basis * qp_result.x;
        result->forces.resize(prepared.num_contacts());
        for (int i = 0; i < prepared.num_contacts(); ++i) result->forces[i] = f.segment<3>(3 * i);
        break;
      }
      case DenseQpStatus::kInfeasible:
        result->status = PlanStatus::kInfeasible;
        result->message = absl::StrCat(
            "no equilibrium force satisfies ",
            prepared.rows.Describe(qp_result.blocking_row, prepared.problem),
            qp_result.active_set.empty()
                ? std::string()
                : absl::StrCat(" together with ", DescribeActive(prepared, qp_result.active_set)));
        break;
      case DenseQpStatus::kIterationLimit:
        result->status = PlanStatus::kSolverFailure;
        result->message = absl::StrCat("active-set iteration limit reached after ",
                                       qp_result.iterations, " iterations");
        break;
      case DenseQpStatus::kNumericalError:
        result->status = PlanStatus::kSolverFailure;
        result->message = "numerical failure in the active-set QP";
        break;
    }
  }
};

}  // namespace

std::unique_ptr<ForceSolver> MakeGeometricSolver() { return std::make_unique<GeometricSolver>(); }

}  // namespace tactforce::planner::internal
