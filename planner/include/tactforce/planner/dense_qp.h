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
  Eigen::MatrixXd hessian;    // H, n x n, SPD
  Eigen::VectorXd gradient;   // g, n
  Eigen::MatrixXd eq_matrix;  // p x n (may have 0 rows)
  Eigen::VectorXd eq_rhs;
  Eigen::MatrixXd in_matrix;  // m x n (may have 0 rows)
  Eigen::VectorXd in_rhs;
  // Optional row structure (the geometric planner's), used when `in_matrix`
  // has no rows, `in_directions` has one row per entry of `in_rhs` and
  // `in_block_first` splits them into consecutive blocks (else ignored): the
  // rows of block b are [in_block_first[b], in_block_first[b + 1]), and row r
  // of it is the 3-vector a_r = in_directions.row(r) applied to the three
  // values y_b = M_b x, M_b = in_block_maps.middleRows<3>(3 b); its normal is
  // M_b^T a_r. A scan of all rows then costs 3 n per block and 3 per row
  // instead of n per row, and a normal is formed only for a row that enters.
  Eigen::Matrix<double, Eigen::Dynamic, 3> in_directions;  // m x 3
  std::vector<int> in_block_first;                         // blocks + 1, from 0 to m
  Eigen::MatrixXd in_block_maps;                           // 3 blocks x n
  // H = I (`hessian` is then ignored): the minimum-norm point of a polytope,
  // the geometric planner's case. Starts from J = I with no factorisation.
  bool identity_hessian = false;
};

struct DenseQpSettings {
  int max_iterations = 0;    // 0 = 5 * (n + m) + 20
  double tolerance = 1e-11;  // relative: violation test and degeneracy
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
// scratch between solves. The sizes below are the parts a solve uses: the
// buffers only grow, so problems whose row count varies below the largest
// seen reuse them without reallocation.
struct DenseQpWorkspace {
  Eigen::MatrixXd normals;         // n x (p + m): constraint normals as columns, formed on demand
  Eigen::VectorXd rhs;             // p + m
  Eigen::VectorXd normal_norms;    // p + m (where formed)
  std::vector<char> has_normal;    // p + m: column formed in this solve
  Eigen::VectorXd distance;        // m: (b - a^T x) / |a| at the last scan
  Eigen::VectorXd inverse_norms;   // m: 1 / |a|
  Eigen::VectorXd distance_bound;  // m: -tolerance max(1, |b|) / |a|; -inf while active
  Eigen::Matrix<double, Eigen::Dynamic, 4> unit_rows;  // m x 4: a_r / |a|, b / |a| (structured)
  Eigen::VectorXd block_values;     // 6 blocks: per-block Gram M_b M_b^T (structured rows)
  Eigen::VectorXd x, d, z, r, u;    // n each (r, u: leading q entries used)
  Eigen::MatrixXd J, R;             // n x n
  Eigen::VectorXd hx;               // n: H x, for the objective
  std::vector<int> active;          // stacked indices, factorisation order
  std::vector<char> is_active;      // p + m
  std::vector<int> pending;         // one per block: violated rows of the last scan not yet tried
  Eigen::LLT<Eigen::MatrixXd> llt;  // H = L L^T (general Hessians only)
};

DenseQpResult SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings = {});

// The same solve in place: `workspace` and `result` keep their storage.
void SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings, DenseQpWorkspace* workspace,
                  DenseQpResult* result);

}  // namespace tactforce::planner
