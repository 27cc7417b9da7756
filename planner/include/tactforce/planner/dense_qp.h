// Small dense strictly convex QP, solved by the Goldfarb-Idnani dual
// active-set method:
//
//   minimise 0.5 x^T H x + g^T x
//   subject to  A_eq x = b_eq,  A_in x <= b_in,   H symmetric positive definite.
//
// Sized for the FE-plane problems of tactforce (tens of variables, hundreds
// of rows). The Ipopt reference cross-checks it.
//
// Two entry points: SolveDenseQp(qp, settings) for one-off use, and the
// in-place overload with a DenseQpWorkspace for control loops: once the
// workspace and the result have seen a problem of the same sizes, a solve
// allocates nothing.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Cholesky>
#include <Eigen/Core>

namespace tactforce::planner {

struct DenseQp {
  Eigen::MatrixXd hessian;  // H, n x n, SPD
  Eigen::VectorXd gradient; // g, n
  Eigen::MatrixXd eq_matrix;  // p x n (may have 0 rows)
  Eigen::VectorXd eq_rhs;
  Eigen::MatrixXd in_matrix;  // m x n (may have 0 rows)
  Eigen::VectorXd in_rhs;
  // H = I (`hessian` is then ignored): the minimum-norm point of a polytope,
  // the geometric planner's case. Starts from J = I with no factorisation.
  bool identity_hessian = false;
};

struct DenseQpSettings {
  int max_iterations = 0;        // 0 = 5 * (n + m) + 20
  double tolerance = 1e-11;      // relative: violation test and degeneracy
  // Inequality rows to try first (previous active set): each is added in
  // this order when violated, which usually finishes in a few steps. Viewed,
  // not copied: must outlive the solve.
  std::span<const int> warm_start;
};

enum class DenseQpStatus { kOptimal, kInfeasible, kIterationLimit, kNumericalError };

struct DenseQpResult {
  DenseQpStatus status = DenseQpStatus::kNumericalError;
  Eigen::VectorXd x;
  double objective = 0.0;
  Eigen::VectorXd in_multipliers;  // >= 0, size m
  Eigen::VectorXd eq_multipliers;  // size p
  std::vector<int> active_set;     // active inequality rows at the end
  int iterations = 0;
  // kInfeasible: the inequality row (or -1 - equality row) that could not be
  // satisfied together with the rows in `active_set`.
  int blocking_row = -1;
};

// Buffers of the active-set method (n variables, p equalities, m
// inequalities), reused from solve to solve. One per thread; contents are
// scratch between solves.
struct DenseQpWorkspace {
  Eigen::MatrixXd normals;      // n x (p + m): constraint normals as columns
  Eigen::VectorXd rhs;          // p + m
  Eigen::VectorXd normal_norms; // p + m
  Eigen::VectorXd slack;        // m
  Eigen::VectorXd x, d, z, r, u;  // n each (r, u: leading q entries used)
  Eigen::MatrixXd J, R;         // n x n
  Eigen::VectorXd hx;           // n: H x, for the objective
  std::vector<int> active;      // stacked indices, factorisation order
  std::vector<char> is_active;  // p + m
  Eigen::LLT<Eigen::MatrixXd> llt;  // H = L L^T (general Hessians only)
};

DenseQpResult SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings = {});

// The same solve in place: `workspace` and `result` keep their storage.
void SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings,
                  DenseQpWorkspace* workspace, DenseQpResult* result);

}  // namespace tactforce::planner
