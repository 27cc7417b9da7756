// The active-set QP is checked against the KKT conditions, which certify
// optimality independently of any other solver.
#include "tactforce/planner/dense_qp.h"

#include <algorithm>
#include <random>

#include <gtest/gtest.h>

#include "support/test_seed.h"

namespace tactforce::planner {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

DenseQp RandomFeasibleQp(std::mt19937& rng, int n, int m, int p) {
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  auto random_matrix = [&](int rows, int cols) {
    MatrixXd a(rows, cols);
    for (int i = 0; i < a.size(); ++i) a.data()[i] = normal(rng);
    return a;
  };
  DenseQp qp;
  const MatrixXd f = random_matrix(n, n);
  qp.hessian = f * f.transpose() + 0.1 * MatrixXd::Identity(n, n);
  qp.gradient = random_matrix(n, 1) * 3.0;
  const VectorXd feasible = random_matrix(n, 1);
  qp.in_matrix = random_matrix(m, n);
  qp.in_rhs = qp.in_matrix * feasible;
  for (int i = 0; i < m; ++i) qp.in_rhs(i) += uniform(rng);  // strictly feasible point exists
  qp.eq_matrix = random_matrix(p, n);
  qp.eq_rhs = qp.eq_matrix * feasible;
  return qp;
}

void ExpectKkt(const DenseQp& qp, const DenseQpResult& r, double tol) {
  ASSERT_EQ(r.status, DenseQpStatus::kOptimal);
  const VectorXd slack = qp.in_rhs - qp.in_matrix * r.x;
  if (slack.size() > 0) EXPECT_GE(slack.minCoeff(), -tol) << "primal infeasible";
  if (qp.eq_matrix.rows() > 0) {
    EXPECT_LE((qp.eq_matrix * r.x - qp.eq_rhs).cwiseAbs().maxCoeff(), tol);
  }
  if (slack.size() > 0) EXPECT_GE(r.in_multipliers.minCoeff(), -tol) << "dual infeasible";
  const VectorXd stationarity = qp.hessian * r.x + qp.gradient +
                                qp.in_matrix.transpose() * r.in_multipliers +
                                qp.eq_matrix.transpose() * r.eq_multipliers;
  EXPECT_LE(stationarity.cwiseAbs().maxCoeff(), tol * 10) << "not stationary";
  for (int i = 0; i < slack.size(); ++i) {
    EXPECT_LE(std::abs(slack(i) * r.in_multipliers(i)), tol * 10) << "complementarity, row " << i;
  }
}

TEST(DenseQp, UnconstrainedMinimum) {
  DenseQp qp;
  qp.hessian = MatrixXd::Identity(3, 3) * 2.0;
  qp.gradient = VectorXd::Constant(3, -2.0);
  qp.in_matrix.resize(0, 3);
  qp.eq_matrix.resize(0, 3);
  const DenseQpResult r = SolveDenseQp(qp);
  ASSERT_EQ(r.status, DenseQpStatus::kOptimal);
  EXPECT_NEAR((r.x - VectorXd::Ones(3)).norm(), 0.0, 1e-14);
  EXPECT_TRUE(r.active_set.empty());
}

TEST(DenseQp, ProjectionOntoHalfSpace) {
  // min 0.5|x|^2 s.t. x0 + x1 >= 2  ->  x = (1, 1), multiplier 1.
  DenseQp qp;
  qp.hessian = MatrixXd::Identity(2, 2);
  qp.gradient = VectorXd::Zero(2);
  qp.in_matrix = MatrixXd(1, 2);
  qp.in_matrix << -1, -1;
  qp.in_rhs = VectorXd::Constant(1, -2.0);
  qp.eq_matrix.resize(0, 2);
  const DenseQpResult r = SolveDenseQp(qp);
  ASSERT_EQ(r.status, DenseQpStatus::kOptimal);
  EXPECT_NEAR(r.x(0), 1.0, 1e-14);
  EXPECT_NEAR(r.x(1), 1.0, 1e-14);
  EXPECT_NEAR(r.in_multipliers(0), 1.0, 1e-14);
  EXPECT_EQ(r.active_set, std::vector<int>{0});
}

TEST(DenseQp, RandomProblemsSatisfyKkt) {
  std::mt19937 rng(20250601);
  for (int trial = 0; trial < 500; ++trial) {
    const int n = 1 + trial % 12;
    const int m = trial % 40;
    const int p = trial % 3 == 0 ? std::min(n - 1, trial % 4) : 0;
    const DenseQp qp = RandomFeasibleQp(rng, n, m, p);
    const DenseQpResult r = SolveDenseQp(qp);
    SCOPED_TRACE(::testing::Message() << "trial " << trial << " n " << n << " m " << m);
    ExpectKkt(qp, r, 1e-8);
  }
}

TEST(DenseQp, WarmStartGivesTheSameAnswerInFewerIterations) {
  std::mt19937 rng(7);
  int cold_iterations = 0, warm_iterations = 0;
  for (int trial = 0; trial < 100; ++trial) {
    const DenseQp qp = RandomFeasibleQp(rng, 8, 30, 0);
    const DenseQpResult cold = SolveDenseQp(qp);
    ASSERT_EQ(cold.status, DenseQpStatus::kOptimal);
    DenseQpSettings settings;
    settings.warm_start = cold.active_set;
    const DenseQpResult warm = SolveDenseQp(qp, settings);
    ExpectKkt(qp, warm, 1e-8);
    EXPECT_LE((warm.x - cold.x).cwiseAbs().maxCoeff(), 1e-9);
    cold_iterations += cold.iterations;
    warm_iterations += warm.iterations;
  }
  EXPECT_LE(warm_iterations, cold_iterations);
}

// An identity-Hessian problem with `blocks` random 3 x n block maps, block
// sizes drawn by `block_size()` and random directions (no right-hand sides).
template <class BlockSize>
DenseQp RandomStructuredQp(std::mt19937& rng, int n, int blocks, BlockSize block_size) {
  std::normal_distribution<double> normal;
  DenseQp qp;
  qp.identity_hessian = true;
  qp.gradient = VectorXd::NullaryExpr(n, [&] { return 3.0 * normal(rng); });
  qp.eq_matrix.resize(0, n);
  qp.in_block_maps = MatrixXd::NullaryExpr(3 * blocks, n, [&] { return normal(rng); });
  qp.in_block_first = {0};
  for (int b = 0; b < blocks; ++b) {
    qp.in_block_first.push_back(qp.in_block_first.back() + block_size());
  }
  const int m = qp.in_block_first.back();
  qp.in_directions = Eigen::MatrixX3d::NullaryExpr(m, 3, [&] { return normal(rng); });
  return qp;
}

// The same rows as a dense matrix, M_b^T a_r each.
DenseQp DenseRowsOf(const DenseQp& structured) {
  DenseQp dense = structured;
  const int blocks = static_cast<int>(structured.in_block_first.size()) - 1;
  dense.in_matrix.resize(structured.in_block_first.back(), structured.gradient.size());
  for (int b = 0; b < blocks; ++b) {
    for (int r = structured.in_block_first[b]; r < structured.in_block_first[b + 1]; ++r) {
      dense.in_matrix.row(r) =
          structured.in_directions.row(r) * structured.in_block_maps.middleRows(3 * b, 3);
    }
  }
  dense.in_directions.resize(0, 3);
  return dense;
}

// The row structure (a_r applied to M_b x) against the same rows as a dense
// matrix: identical statuses, answers to round-off, the same blocking row.
// Sizes, blocks and warm starts are drawn from the seed; some problems get an
// infeasible pair of rows.
TEST(DenseQp, RowStructureAnswersAsTheDenseRows) {
  std::mt19937 rng(2029);
  std::normal_distribution<double> normal;
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  int infeasible = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const int n = 1 + trial % 14;  // covers the fixed sizes 1..12 and beyond
    const int blocks = 1 + static_cast<int>(uniform(rng) * 6);
    DenseQp structured =
        RandomStructuredQp(rng, n, blocks, [&] { return 1 + static_cast<int>(uniform(rng) * 8); });
    const int m = structured.in_block_first.back();
    DenseQp dense = DenseRowsOf(structured);
    const VectorXd feasible = VectorXd::NullaryExpr(n, [&] { return normal(rng); });
    structured.in_rhs = dense.in_matrix * feasible;
    for (int i = 0; i < m; ++i) structured.in_rhs(i) += uniform(rng);
    if (trial % 5 == 4 && m >= 2) {  // row 1 = -row 0 with rhs making them inconsistent
      const int b0 = 0;
      if (structured.in_block_first[b0 + 1] >= 2) {
        structured.in_directions.row(1) = -structured.in_directions.row(0);
        dense.in_matrix.row(1) = -dense.in_matrix.row(0);
        structured.in_rhs(1) = -structured.in_rhs(0) - 1.0;
      }
    }
    dense.in_rhs = structured.in_rhs;
    const DenseQpResult a = SolveDenseQp(structured);
    const DenseQpResult b = SolveDenseQp(dense);
    ASSERT_EQ(a.status, b.status) << trial;
    if (a.status == DenseQpStatus::kInfeasible) {
      ++infeasible;
      EXPECT_GE(a.blocking_row, 0) << trial;
      continue;
    }
    ASSERT_EQ(a.status, DenseQpStatus::kOptimal) << trial;
    EXPECT_LE((a.x - b.x).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, b.x.norm())) << trial;
    DenseQp check = dense;
    check.hessian = MatrixXd::Identity(n, n);
    ExpectKkt(check, a, 1e-8);
    // Warm-started from the answer: the same point.
    DenseQpSettings settings;
    settings.warm_start = a.active_set;
    const DenseQpResult warm = SolveDenseQp(structured, settings);
    EXPECT_LE((warm.x - a.x).cwiseAbs().maxCoeff(), 1e-9 * std::max(1.0, a.x.norm())) << trial;
  }
  EXPECT_GT(infeasible, 0);
}

// Structured rows whose normal M_b^T a_r is exactly zero (a_r along a zero
// row of M_b), at drawn positions among ordinary rows of drawn blocks, against
// the same rows as a dense matrix: 0^T x <= b with b >= 0 changes nothing,
// with b < 0 both solves are infeasible and name the first such row.
TEST(DenseQp, StructuredZeroRowsAreIgnoredOrNamed) {
  std::mt19937 rng(static_cast<unsigned>(tactforce::testing::GtestSeed()));
  std::normal_distribution<double> normal;
  std::uniform_int_distribution<int> count(1, 9);
  for (int trial = 0; trial < 100; ++trial) {
    const int n = 3 + trial % 10, blocks = 1 + trial % 4;
    DenseQp qp = RandomStructuredQp(rng, n, blocks, [&] { return count(rng); });
    for (int b = 0; b < blocks; ++b) {
      qp.in_block_maps.row(3 * b + 2).setZero();  // (0, 0, c) has a zero normal
    }
    const int m = qp.in_block_first.back();
    qp.in_rhs = VectorXd::NullaryExpr(m, [&] { return 0.5 + std::abs(normal(rng)); });
    std::vector<int> zero_rows;
    for (int r = 0; r < m; ++r) {
      if (count(rng) > 3) continue;
      qp.in_directions.row(r) << 0.0, 0.0, normal(rng);
      zero_rows.push_back(r);
    }
    DenseQp dense = DenseRowsOf(qp);
    const DenseQpResult structured = SolveDenseQp(qp);
    const DenseQpResult reference = SolveDenseQp(dense);
    ASSERT_EQ(structured.status, DenseQpStatus::kOptimal) << trial;  // x = 0 is feasible
    ASSERT_EQ(reference.status, DenseQpStatus::kOptimal) << trial;
    EXPECT_LE((structured.x - reference.x).cwiseAbs().maxCoeff(),
              1e-9 * std::max(1.0, reference.x.norm()))
        << trial;
    if (zero_rows.empty()) continue;
    for (DenseQp* problem : {&qp, &dense}) {
      problem->in_rhs(zero_rows.back()) = -1.0;
      if (zero_rows.size() > 1) problem->in_rhs(zero_rows.front()) = -2.0;
      const DenseQpResult named = SolveDenseQp(*problem);
      EXPECT_EQ(named.status, DenseQpStatus::kInfeasible) << trial;
      EXPECT_EQ(named.blocking_row, zero_rows.front()) << trial;
    }
  }
}

TEST(DenseQp, DetectsInfeasibilityAndNamesTheRow) {
  // x0 >= 1 and x0 <= -1 cannot both hold.
  DenseQp qp;
  qp.hessian = MatrixXd::Identity(2, 2);
  qp.gradient = VectorXd::Zero(2);
  qp.in_matrix = MatrixXd(3, 2);
  qp.in_matrix << 0, 1, -1, 0, 1, 0;
  qp.in_rhs = VectorXd(3);
  qp.in_rhs << 5, -1, -1;
  qp.eq_matrix.resize(0, 2);
  const DenseQpResult r = SolveDenseQp(qp);
  EXPECT_EQ(r.status, DenseQpStatus::kInfeasible);
  EXPECT_TRUE(r.blocking_row == 1 || r.blocking_row == 2) << r.blocking_row;
}

TEST(DenseQp, RandomInfeasibleProblemsAreDetected) {
  std::mt19937 rng(99);
  std::normal_distribution<double> normal;
  for (int trial = 0; trial < 200; ++trial) {
    DenseQp qp = RandomFeasibleQp(rng, 2 + trial % 6, 10, 0);
    // Append a^T x <= -1 for a row a already bounded below: a^T x >= 0 and a^T x <= -1.
    const int n = static_cast<int>(qp.gradient.size());
    VectorXd a(n);
    for (int i = 0; i < n; ++i) a(i) = normal(rng);
    qp.in_matrix.conservativeResize(12, n);
    qp.in_rhs.conservativeResize(12);
    qp.in_matrix.row(10) = -a.transpose();
    qp.in_rhs(10) = 0.0;
    qp.in_matrix.row(11) = a.transpose();
    qp.in_rhs(11) = -1.0;
    EXPECT_EQ(SolveDenseQp(qp).status, DenseQpStatus::kInfeasible) << "trial " << trial;
  }
}

TEST(DenseQp, InconsistentEqualitiesAreInfeasible) {
  DenseQp qp;
  qp.hessian = MatrixXd::Identity(2, 2);
  qp.gradient = VectorXd::Zero(2);
  qp.eq_matrix = MatrixXd(2, 2);
  qp.eq_matrix << 1, 1, 2, 2;
  qp.eq_rhs = VectorXd(2);
  qp.eq_rhs << 1, 3;
  qp.in_matrix.resize(0, 2);
  EXPECT_EQ(SolveDenseQp(qp).status, DenseQpStatus::kInfeasible);
  qp.eq_rhs << 1, 2;  // redundant but consistent
  const DenseQpResult r = SolveDenseQp(qp);
  ASSERT_EQ(r.status, DenseQpStatus::kOptimal);
  EXPECT_NEAR(r.x(0), 0.5, 1e-12);
  EXPECT_NEAR(r.x(1), 0.5, 1e-12);
}

}  // namespace
}  // namespace tactforce::planner
