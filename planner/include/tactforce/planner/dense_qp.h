// Small dense strictly convex QP, solved by the Goldfarb-Idnani dual
// active-set method:
//
//   minimise 0.5 x^T H x + g^T x
//   subject to  A_eq x = b_eq,  A_in x <= b_in,   H symmetric positive definite.
//
// Sized for the FE-plane problems of tactforce (tens of variables, hundreds
// of rows). The Ipopt reference cross-checks it.
#pragma once

#include <vector>

#include <Eigen/Core>

namespace tactforce::planner {

struct DenseQp {
  Eigen::MatrixXd hessian;  // H, n x n, SPD
  Eigen::VectorXd gradient; // g, n
  Eigen::MatrixXd eq_matrix;  // p x n (may have 0 rows)
  Eigen::VectorXd eq_rhs;
  Eigen::MatrixXd in_matrix;  // m x n (may have 0 rows)
  Eigen::VectorXd in_rhs;
};

struct DenseQpSettings {
  int max_iterations = 0;        // 0 = 5 * (n + m) + 20
  double tolerance = 1e-11;      // relative: violation test and degeneracy
  // Inequality rows to try first (previous active set): each is added in
  // this order when violated, which usually finishes in a few steps.
  std::vector<int> warm_start;
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

DenseQpResult SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings = {});

}  // namespace tactforce::planner
