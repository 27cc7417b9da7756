#include "tactforce/planner/force_model.h"
#include "support/test_seed.h"

#include <cmath>
#include <numbers>
#include <random>

#include <Eigen/SVD>
#include <gtest/gtest.h>

namespace tactforce::planner {
namespace {

Contact MakeContact(const Vec3& p, const Vec3& n, double sigma = 0.0) {
  Contact c;
  c.position = p;
  c.normal = n.normalized();
  c.friction = 0.5;
  c.sigma = sigma;
  return c;
}

PlanProblem ThreeFingerProblem() {
  PlanProblem p;
  p.object.mass = 0.3;
  p.object.com = Vec3(0.01, 0.002, -0.003);
  p.contacts = {MakeContact({0.02, 0.012, 0}, {0, -1, 0}, 0.5),
                MakeContact({-0.02, 0.012, 0}, {0, -1, 0.1}, 0.2),
                MakeContact({0.0, -0.012, 0.01}, {0, 1, 0}, 0.3)};
  p.external_wrench.force = Vec3(0.1, -0.2, 0.3);
  p.external_wrench.torque = Vec3(0.01, 0.0, -0.02);
  return p;
}

TEST(ForceEquilibrium, NullBasisIsOrthonormalAndSpansTheKernel) {
  const PlanProblem p = ThreeFingerProblem();
  const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
  EXPECT_EQ(eq.rank, 6);
  ASSERT_EQ(eq.null_basis.cols(), 3);
  EXPECT_LE((eq.grasp_matrix * eq.null_basis).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LE(
      (eq.null_basis.transpose() * eq.null_basis - MatrixXd::Identity(3, 3)).cwiseAbs().maxCoeff(),
      1e-14);
  // f0 = G^+ b, compared with an independent pseudo-inverse.
  const MatrixXd pinv = eq.grasp_matrix.completeOrthogonalDecomposition().pseudoInverse();
  EXPECT_LE((eq.particular - pinv * eq.wrench).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_TRUE(eq.consistent);
  EXPECT_LE(eq.residual, 1e-12);
  EXPECT_LE(std::abs((eq.null_basis.transpose() * eq.particular).norm()), 1e-13);
}

TEST(ForceEquilibrium, WrenchIncludesGravityAndExternalWrench) {
  const PlanProblem p = ThreeFingerProblem();
  const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
  const Vec3 weight = p.object.mass * p.object.gravity;
  EXPECT_LE((eq.wrench.head<3>() + weight + p.external_wrench.force).norm(), 1e-15);
  EXPECT_LE((eq.wrench.tail<3>() + p.object.com.cross(weight) + p.external_wrench.torque).norm(),
            1e-15);
}

TEST(ForceEquilibrium, AntipodalPairHasRankFive) {
  PlanProblem p;
  p.object.mass = 0.1;
  p.contacts = {MakeContact({-0.03, 0, 0}, {1, 0, 0}), MakeContact({0.03, 0, 0}, {-1, 0, 0})};
  const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
  EXPECT_EQ(eq.rank, 5);
  EXPECT_EQ(eq.null_basis.cols(), 1);
  // Weight through the axis: consistent. The kernel is the squeeze direction.
  EXPECT_TRUE(eq.consistent);
  const VectorXd b = eq.null_basis.col(0);
  EXPECT_NEAR(std::abs(b(0)), std::sqrt(0.5), 1e-12);
  EXPECT_NEAR(b(0), -b(3), 1e-12);
  // A torque about the axis cannot be resisted.
  p.external_wrench.torque = Vec3(0.01, 0, 0);
  const ForceEquilibrium bad = ComputeForceEquilibrium(p, 1e-9);
  EXPECT_FALSE(bad.consistent);
  EXPECT_NEAR(bad.residual, 0.01, 1e-12);
}

TEST(ForceEquilibrium, CollinearContactsLoseOneRotation) {
  PlanProblem p;
  p.object.mass = 0.1;
  p.object.com = Vec3(0.01, 0, 0);  // on the line: weight torque has no x part
  p.contacts = {MakeContact({-0.03, 0, 0}, {0, 0, 1}), MakeContact({0.0, 0, 0}, {0, 0, 1}),
                MakeContact({0.05, 0, 0}, {0, 0, 1})};
  const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
  EXPECT_EQ(eq.rank, 5);
  EXPECT_EQ(eq.null_basis.cols(), 9 - 5);
  EXPECT_TRUE(eq.consistent);
  EXPECT_EQ(eq.independent_rows.rows(), 5);
  EXPECT_LE((eq.independent_rows * eq.particular - eq.independent_rhs).norm(), 1e-14);
}

// Generic, collinear and coincident contacts, 1 to 8 of them, drawn from a
// fixed seed and from gtest's: the FE-plane against an independent
// pseudo-inverse (Eigen's complete orthogonal decomposition of G), on both
// rank paths (bounds, and the 3x3 SVD when the torque block is singular).
TEST(ForceEquilibrium, BasesMatchAnIndependentDecompositionOnEveryRankPath) {
  for (const unsigned seed : {29u, static_cast<unsigned>(::tactforce::testing::GtestSeed())}) {
    std::mt19937 rng(seed);
    std::normal_distribution<double> g;
    for (int trial = 0; trial < 60; ++trial) {
      const int n = 1 + trial % 8;
      const int kind = (trial / 8) % 3;  // 0 generic, 1 collinear, 2 coincident
      const Vec3 axis = Vec3(g(rng), g(rng), g(rng)).normalized();
      const Vec3 base = 0.02 * Vec3(g(rng), g(rng), g(rng));
      PlanProblem p;
      p.object.mass = 0.2;
      p.object.com = base;  // on the line and at the point: a consistent wrench
      for (int i = 0; i < n; ++i) {
        const Vec3 pos = kind == 0   ? Vec3(0.03 * Vec3(g(rng), g(rng), g(rng)))
                         : kind == 1 ? Vec3(base + 0.03 * g(rng) * axis)
                                     : base;
        p.contacts.push_back(MakeContact(pos, Vec3(g(rng), g(rng), g(rng))));
      }
      // One or two contacts resist only a wrench whose line passes through the first.
      if (n <= 2) p.object.com = p.contacts[0].position;
      SCOPED_TRACE(::testing::Message() << "seed " << seed << " trial " << trial);
      const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
      const int expected_rank = std::min(3 * n, kind == 2 ? 3 : kind == 1 || n == 2 ? 5 : 6);
      ASSERT_EQ(eq.rank, n == 1 ? 3 : expected_rank);
      const MatrixXd& b = eq.null_basis;
      ASSERT_EQ(b.cols(), 3 * n - eq.rank);
      ASSERT_EQ(eq.independent_rows.rows(), eq.rank);
      MatrixXd basis(3 * n, 3 * n);
      basis.leftCols(eq.rank) = eq.independent_rows.transpose();
      basis.rightCols(b.cols()) = b;
      EXPECT_LE(
          (basis.transpose() * basis - MatrixXd::Identity(3 * n, 3 * n)).cwiseAbs().maxCoeff(),
          1e-13);
      if (b.cols() > 0) EXPECT_LE((eq.grasp_matrix * b).cwiseAbs().maxCoeff(), 1e-14);
      const MatrixXd pinv = eq.grasp_matrix.completeOrthogonalDecomposition().pseudoInverse();
      EXPECT_LE((eq.particular - pinv * eq.wrench).cwiseAbs().maxCoeff(),
                1e-12 * std::max(1.0, eq.wrench.norm()));
      EXPECT_TRUE(eq.consistent);
      EXPECT_LE((eq.independent_rows * eq.particular - eq.independent_rhs).norm(), 1e-13);
    }
  }
}

TEST(TangentBasis, FollowsTheStatedConvention) {
  const auto [t1, t2] = TangentBasis(Vec3(0, 0, 1));
  EXPECT_LE((t1 - Vec3(1, 0, 0)).norm(), 1e-15);  // x is first on ties
  EXPECT_LE((t2 - Vec3(0, 1, 0)).norm(), 1e-15);
  std::mt19937 rng(3);
  std::normal_distribution<double> g;
  for (int i = 0; i < 100; ++i) {
    const Vec3 n = Vec3(g(rng), g(rng), g(rng)).normalized();
    const auto [a, b] = TangentBasis(n);
    EXPECT_NEAR(a.dot(n), 0, 1e-14);
    EXPECT_NEAR(b.dot(n), 0, 1e-14);
    EXPECT_NEAR(a.norm(), 1, 1e-14);
    EXPECT_NEAR(a.cross(b).dot(n), 1, 1e-14);  // right-handed (t1, t2, n)
  }
}

TEST(MeasurementEllipsoid, MatchesTheDefinition) {
  const PlanProblem p = ThreeFingerProblem();
  const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
  const MeasurementEllipsoid e = ComputeMeasurementEllipsoid(p, eq);
  // S_f = B E diag(sigma^2) E^T B^T, E = B^T N_I, written out directly.
  MatrixXd n_i = MatrixXd::Zero(9, 3);
  Eigen::VectorXd sigma2(3);
  for (int j = 0; j < 3; ++j) {
    n_i.block<3, 1>(3 * j, j) = p.contacts[j].normal;
    sigma2(j) = p.contacts[j].sigma * p.contacts[j].sigma;
  }
  const MatrixXd E = eq.null_basis.transpose() * n_i;
  const MatrixXd s_x = E * sigma2.asDiagonal() * E.transpose();
  const MatrixXd s_f = eq.null_basis * s_x * eq.null_basis.transpose();
  EXPECT_LE((e.ForceCovariance() - s_f).cwiseAbs().maxCoeff(), 1e-14);
  const VectorXd a = VectorXd::LinSpaced(9, -1, 1);
  EXPECT_NEAR(e.Support(a), std::sqrt(a.dot(s_f * a)), 1e-14);
  // Noise stays on the FE-plane: G S_f = 0.
  EXPECT_LE((eq.grasp_matrix * s_f).cwiseAbs().maxCoeff(), 1e-14);
}

TEST(MeasurementEllipsoid, ExtrinsicContactsAddNoNoise) {
  PlanProblem p = ThreeFingerProblem();
  for (Contact& c : p.contacts) c.kind = ContactKind::kExtrinsic;
  const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
  const MeasurementEllipsoid e = ComputeMeasurementEllipsoid(p, eq);
  EXPECT_EQ(e.ForceCovariance().norm(), 0.0);
}

TEST(ConstraintRows, PyramidRowsAndRobustTightening) {
  const PlanProblem p = ThreeFingerProblem();
  const ForceEquilibrium eq = ComputeForceEquilibrium(p, 1e-9);
  const MeasurementEllipsoid e = ComputeMeasurementEllipsoid(p, eq);
  const int k = 8;
  const ConstraintRows rows = BuildConstraintRows(p, e, k, 2.0, true);
  ASSERT_EQ(rows.directions.rows(), 3 * (k + 1));
  for (int r = 0; r < rows.directions.rows(); ++r) {
    const VectorXd a = rows.Dense(static_cast<int>(p.contacts.size())).row(r).transpose();
    EXPECT_NEAR(rows.nominal_rhs(r) - rows.rhs(r), 2.0 * e.Support(a), 1e-14);
  }
  // Facet j of contact 0: u_j - mu cos(pi/k) n, u_j = cos t1 + sin t2.
  const auto [t1, t2] = TangentBasis(p.contacts[0].normal);
  const double th = 2 * std::numbers::pi * 3 / k;
  const Vec3 expected = std::cos(th) * t1 + std::sin(th) * t2 -
                        0.5 * std::cos(std::numbers::pi / k) * p.contacts[0].normal;
  EXPECT_LE((rows.directions.row(3).transpose() - expected).norm(), 1e-15);
  EXPECT_EQ(rows.Describe(3, p), "contact 0 friction cone facet 3");
  EXPECT_EQ(rows.Describe(k, p), "contact 0 minimum normal force");
}

// shift = kappa (mu rho_n + rho_t), computed once in Prepare; the slack
// mu n.f - shift - |P f| is zero on the robust cone's surface.
TEST(ExactCone, ShiftAndSlackOfTheRobustCone) {
  PlanOptions o;
  o.cone = ConeModel::kExact;
  o.confidence = 2.0;
  const PreparedProblem prepared = Prepare(ThreeFingerProblem(), o);
  ASSERT_EQ(prepared.cone_shift.size(), 3u);
  for (int i = 0; i < 3; ++i) {
    const Contact& c = prepared.problem.contacts[i];
    EXPECT_GT(prepared.tangential_sigma[i], 0.0);
    EXPECT_NEAR(prepared.cone_shift[i],
                2.0 * (c.friction * prepared.normal_sigma[i] + prepared.tangential_sigma[i]),
                1e-15);
    const double shift = prepared.cone_shift[i];
    const auto [t1, t2] = TangentBasis(c.normal);
    const double fn = 3.0;
    const Vec3 on_surface = fn * c.normal + (c.friction * fn - shift) * (0.6 * t1 + 0.8 * t2);
    EXPECT_NEAR(ExactConeSlack(c.normal, c.friction, shift, on_surface), 0.0, 1e-14);
    EXPECT_NEAR(ExactConeSlack(c.normal, c.friction, shift, fn * c.normal), c.friction * fn - shift,
                1e-14);
    EXPECT_NEAR(ExactConeSlack(c.normal, c.friction, shift, on_surface + 0.5 * t2),
                -(on_surface + 0.5 * t2 - fn * c.normal).norm() + (c.friction * fn - shift), 1e-14);
  }
  o.confidence = 0.0;
  const std::vector<double> untightened = Prepare(ThreeFingerProblem(), o).cone_shift;
  EXPECT_EQ(untightened, std::vector<double>(3, 0.0));
  o.cone = ConeModel::kPyramid;  // the facets carry the tightening
  EXPECT_TRUE(Prepare(ThreeFingerProblem(), o).cone_shift.empty());
}

TEST(ContactLabel, IndexAndNameWhenThereIsOne) {
  PlanProblem p = ThreeFingerProblem();
  p.contacts[1].name = "thumb";
  EXPECT_EQ(ContactLabel(p, 0), "contact 0");
  EXPECT_EQ(ContactLabel(p, 1), "contact 1 (thumb)");
}

}  // namespace
}  // namespace tactforce::planner
