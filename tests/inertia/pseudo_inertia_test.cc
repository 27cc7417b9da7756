// The inertia value types (pseudo_inertia.h) on random physically consistent
// bodies drawn from a seed: bit-identical to the constructions they replaced
// (metrics' pseudo-inertia, the factor graph's Pseudo<T>, CONSTRAINED's
// U(theta) and DENSITY's map from the standard parameters), round trips, and
// the scalar template under Eigen's AutoDiff.
#include "tactforce/inertia/pseudo_inertia.h"

#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>
#include <gtest/gtest.h>
#include <unsupported/Eigen/AutoDiff>

#include "tactforce/inertia/metrics.h"

namespace tactforce::inertia {
namespace {

// A consistent body: second moment about the CoM R diag(s) R^T, s > 0.
InertialParameters RandomBody(std::mt19937_64* rng) {
  std::uniform_real_distribution<double> mass(0.05, 5.0), pos(-0.2, 0.2), moment(1e-6, 1e-2),
      unit(-1, 1);
  InertialParameters p;
  p.mass = mass(*rng);
  p.com = Vec3(pos(*rng), pos(*rng), pos(*rng));
  const Eigen::Matrix3d R = Eigen::Quaterniond(unit(*rng), unit(*rng), unit(*rng), unit(*rng))
                                .normalized()
                                .toRotationMatrix();
  const Eigen::Matrix3d sigma_c =
      p.mass * R * Vec3(moment(*rng), moment(*rng), moment(*rng)).asDiagonal() * R.transpose();
  p.inertia_com =
      InertiaTensor::FromMatrix(sigma_c.trace() * Eigen::Matrix3d::Identity() - sigma_c);
  return p;
}

// Reference: the pseudo-inertia as metrics.cc, DENSITY and the factor graph
// built it before the value types, written out from eq. 21.
Eigen::Matrix4d ReferencePseudo(const InertialParameters& p) {
  const Eigen::Matrix3d io = p.InertiaOrigin();
  Eigen::Matrix4d P = Eigen::Matrix4d::Zero();
  P.topLeftCorner<3, 3>() = 0.5 * io.trace() * Eigen::Matrix3d::Identity() - io;
  P.topRightCorner<3, 1>() = p.mass * p.com;
  P.bottomLeftCorner<1, 3>() = (p.mass * p.com).transpose();
  P(3, 3) = p.mass;
  return P;
}

double RelativeDifference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return (a - b).norm() / std::max(a.norm(), 1e-300);
}

class PseudoInertiaTypes : public ::testing::TestWithParam<int> {};

TEST_P(PseudoInertiaTypes, MatchesTheEquationBitForBit) {
  std::mt19937_64 rng(GetParam());
  for (int trial = 0; trial < 200; ++trial) {
    const InertialParameters p = RandomBody(&rng);
    const Eigen::Matrix4d ref = ReferencePseudo(p);
    const PseudoInertiaD j = PseudoInertiaD::FromParameters(p);
    EXPECT_TRUE((j.Matrix().array() == ref.array()).all()) << "trial " << trial;
    EXPECT_TRUE((PseudoInertia(p).array() == ref.array()).all());
    // Standard parameters: J is linear in pi and Standard() inverts it.
    const Vector10d pi = p.ToStandard();
    EXPECT_TRUE((PseudoInertiaD::FromStandard(pi).Matrix().array() == ref.array()).all());
    EXPECT_LT(RelativeDifference(j.Standard(), pi), 1e-14);
    const InertialParameters back = j.Parameters();
    EXPECT_LT(RelativeDifference(back.ToStandard(), pi), 1e-12);
    EXPECT_LT(std::abs(back.mass - p.mass), 1e-15 * p.mass);
    // Entries in log-Cholesky order and back.
    const PseudoInertiaD again = PseudoInertiaD::FromEntries(j.Entries());
    EXPECT_TRUE((again.Matrix().array() == ref.array()).all());
    EXPECT_EQ(j.Entries()(LogCholeskyParameters::Index(3, 3)), p.mass);
    EXPECT_EQ(j.Entries()(LogCholeskyParameters::Index(2, 0)), ref(0, 2));
  }
}

TEST_P(PseudoInertiaTypes, LogCholeskyRoundTrips) {
  std::mt19937_64 rng(1000 + GetParam());
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const InertialParameters p = RandomBody(&rng);
    const PseudoInertiaD j = PseudoInertiaD::FromParameters(p);
    const LogCholeskyParameters lc = LogCholeskyParameters::FromPseudoInertia(j);
    ASSERT_TRUE(lc.theta.allFinite());
    // U is upper triangular with a positive diagonal and U U^T = J.
    const Eigen::Matrix4d U = lc.U();
    EXPECT_TRUE(U.isUpperTriangular(0.0));
    EXPECT_TRUE((U.diagonal().array() > 0).all());
    EXPECT_LT(RelativeDifference(lc.ToPseudoInertia().Matrix(), j.Matrix()), 1e-12)
        << "trial " << trial;
    EXPECT_LT(RelativeDifference(lc.ToPseudoInertia().Standard(), p.ToStandard()), 1e-12);
    // Every theta is a consistent body, and theta -> J -> theta is the identity.
    LogCholeskyParameters any;
    for (int k = 0; k < 10; ++k) any.theta(k) = (k < 4 ? -3.0 : 0.0) + 0.5 * normal(rng);
    const PseudoInertiaD jt = any.ToPseudoInertia();
    EXPECT_TRUE(IsPhysicallyConsistent(jt.Parameters(), 0.0));
    // theta -> J -> theta loses digits with the condition number of J.
    const LogCholeskyParameters back = LogCholeskyParameters::FromPseudoInertia(jt);
    const Eigen::Vector4d ev =
        Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d>(jt.Matrix()).eigenvalues();
    EXPECT_LT((back.theta - any.theta).norm(), 1e-14 * ev(3) / ev(0) * any.theta.norm());
    EXPECT_LT(RelativeDifference(back.ToPseudoInertia().Matrix(), jt.Matrix()), 1e-12);
  }
}

INSTANTIATE_TEST_SUITE_P(Seeds, PseudoInertiaTypes, ::testing::Values(1, 2, 3));

TEST(PseudoInertiaTypes, AutoDiffDerivativesMatchTheLinearMap) {
  // J is linear in pi: d J / d pi_k = J(e_k), exactly, through AutoDiffScalar.
  using Jet = Eigen::AutoDiffScalar<Eigen::Matrix<double, 10, 1>>;
  std::mt19937_64 rng(7);
  const Vector10d pi = RandomBody(&rng).ToStandard();
  Eigen::Matrix<Jet, 10, 1> x;
  for (int k = 0; k < 10; ++k) x(k) = Jet(pi(k), 10, k);
  const Eigen::Matrix<Jet, 4, 4> J = PseudoInertiaTpl<Jet>::FromStandard(x).Matrix();
  for (int k = 0; k < 10; ++k) {
    const Eigen::Matrix4d dk = PseudoInertiaD::FromStandard(Vector10d::Unit(k)).Matrix();
    for (int r = 0; r < 4; ++r)
      for (int c = 0; c < 4; ++c) {
        EXPECT_EQ(J(r, c).value(), PseudoInertiaD::FromStandard(pi).Matrix()(r, c));
        EXPECT_EQ(J(r, c).derivatives()(k), dk(r, c)) << k << " " << r << " " << c;
      }
  }
}

}  // namespace
}  // namespace tactforce::inertia
