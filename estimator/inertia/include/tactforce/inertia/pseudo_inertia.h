// The three forms of a rigid body's inertia and their conversions, templated
// on the scalar so that the factor graph differentiates through them
// (Eigen's AutoDiffScalar) and the other methods use them with double:
//
//   Inertia                  InertialParameters (types.h): mass, CoM and the
//                            inertia about the CoM, object frame.
//   standard parameters pi   [m, m cx, m cy, m cz, Ixx, Iyy, Izz, Ixy, Ixz, Iyz],
//                            the inertia about the OBJECT ORIGIN (the order of
//                            planner/types.h and InertialParameters::ToStandard).
//   PseudoInertiaTpl         J = [[Sigma, h], [h^T, m]]: Sigma = 1/2 tr(I_o) 1 - I_o
//                            the second moment of the mass about the origin
//                            (kg m^2), h = m c (kg m), m (kg). Linear in pi;
//                            the parameters are physically consistent iff J is
//                            positive definite (Wensing, Kim & Slotine 2017).
//   LogCholeskyParametersTpl J = U U^T with U upper triangular and a positive
//                            diagonal, theta = [log U00, log U11, log U22,
//                            log U33, U01, U02, U03, U12, U13, U23]: every
//                            theta in R^10 is a consistent body (Rucker &
//                            Wensing 2022).
//
// The 10 entries of J in LogCholeskyParametersTpl::kRow/kCol order (J00, J11,
// J22, J33, J01, J02, J03, J12, J13, J23: entry k is J(kRow[k], kCol[k]),
// the same positions as theta's entries in U) are the coordinates in which
// CONSTRAINED writes its quadratic model (PseudoInertiaTpl::Entries).
#pragma once

#include <algorithm>
#include <cmath>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

template <typename Scalar>
struct PseudoInertiaTpl {
  using Vector3 = Eigen::Matrix<Scalar, 3, 1>;
  using Matrix3 = Eigen::Matrix<Scalar, 3, 3>;
  using Matrix4 = Eigen::Matrix<Scalar, 4, 4>;
  using Vector10 = Eigen::Matrix<Scalar, 10, 1>;

  Scalar mass = Scalar(0);          // m (kg)
  Vector3 h = Vector3::Zero();      // m c (kg m)
  Matrix3 sigma = Matrix3::Zero();  // second moment about the origin (kg m^2)

  // From the standard parameters pi (inertia about the origin).
  template <typename Derived>
  static PseudoInertiaTpl FromStandard(const Eigen::MatrixBase<Derived>& pi) {
    Matrix3 io;
    io << pi(4), pi(7), pi(8), pi(7), pi(5), pi(9), pi(8), pi(9), pi(6);
    PseudoInertiaTpl j;
    j.mass = pi(0);
    j.h = pi.template segment<3>(1);
    j.sigma = Scalar(0.5) * io.trace() * Matrix3::Identity() - io;
    return j;
  }
  // From mass, CoM and inertia about the CoM (double only).
  static PseudoInertiaTpl FromParameters(const InertialParameters& p) {
    return FromStandard(p.ToStandard());
  }
  // From a 4x4 matrix: its upper triangle (J need not be positive definite).
  template <typename Derived>
  static PseudoInertiaTpl FromMatrix(const Eigen::MatrixBase<Derived>& J) {
    PseudoInertiaTpl j;
    j.mass = J(3, 3);
    j.h = J.template topRightCorner<3, 1>();
    for (int r = 0; r < 3; ++r)
      for (int c = r; c < 3; ++c) j.sigma(r, c) = j.sigma(c, r) = J(r, c);
    return j;
  }
  // From the 10 entries in kRow/kCol order (Entries()).
  static PseudoInertiaTpl FromEntries(const Vector10& e);

  Matrix4 Matrix() const {
    Matrix4 J;
    J.template topLeftCorner<3, 3>() = sigma;
    J.template topRightCorner<3, 1>() = h;
    J.template bottomLeftCorner<1, 3>() = h.transpose();
    J(3, 3) = mass;
    return J;
  }
  Vector10 Standard() const {
    const Matrix3 io = sigma.trace() * Matrix3::Identity() - sigma;
    Vector10 pi;
    pi << mass, h(0), h(1), h(2), io(0, 0), io(1, 1), io(2, 2), io(0, 1), io(0, 2), io(1, 2);
    return pi;
  }
  // Mass, CoM and inertia about the CoM (double only; CoM 0 when m == 0).
  InertialParameters Parameters() const { return InertialParameters::FromStandard(Standard()); }
  Vector10 Entries() const;
};

template <typename Scalar>
struct LogCholeskyParametersTpl {
  using Matrix4 = Eigen::Matrix<Scalar, 4, 4>;
  using Vector10 = Eigen::Matrix<Scalar, 10, 1>;

  // Entry k of theta is U(kRow[k], kCol[k]) (its log for k < 4); entry k of
  // PseudoInertiaTpl::Entries() is J(kRow[k], kCol[k]).
  static constexpr int kRow[10] = {0, 1, 2, 3, 0, 0, 0, 1, 1, 2};
  static constexpr int kCol[10] = {0, 1, 2, 3, 1, 2, 3, 2, 3, 3};
  // Index k of the entry at (i, j) (either order), i, j in 0..3.
  static constexpr int Index(int i, int j) {
    if (i > j) return Index(j, i);
    for (int k = 0; k < 10; ++k)
      if (kRow[k] == i && kCol[k] == j) return k;
    return -1;
  }

  Vector10 theta = Vector10::Zero();

  Matrix4 U() const {
    using std::exp;
    Matrix4 u = Matrix4::Zero();
    for (int k = 0; k < 10; ++k) u(kRow[k], kCol[k]) = k < 4 ? Scalar(exp(theta(k))) : theta(k);
    return u;
  }
  PseudoInertiaTpl<Scalar> ToPseudoInertia() const {
    const Matrix4 u = U();
    return PseudoInertiaTpl<Scalar>::FromMatrix(Matrix4(u * u.transpose()));
  }
  // The factor of a positive definite J (double only): J = U U^T, U upper
  // triangular, by the Cholesky factor of the index-reversed matrix. Not
  // positive definite: a diagonal entry of U is floored at 1e-300 before its log.
  static LogCholeskyParametersTpl FromPseudoInertia(const PseudoInertiaTpl<Scalar>& j) {
    const Matrix4 X = j.Matrix().reverse();
    const Eigen::LLT<Matrix4> llt(Scalar(0.5) * (X + X.transpose()));
    const Matrix4 L = llt.matrixL();
    const Matrix4 u = L.reverse();
    LogCholeskyParametersTpl lc;
    for (int k = 0; k < 10; ++k) {
      const Scalar v = u(kRow[k], kCol[k]);
      lc.theta(k) = k < 4 ? Scalar(std::log(std::max(v, Scalar(1e-300)))) : v;
    }
    return lc;
  }
};

template <typename Scalar>
typename PseudoInertiaTpl<Scalar>::Vector10 PseudoInertiaTpl<Scalar>::Entries() const {
  using LC = LogCholeskyParametersTpl<Scalar>;
  Vector10 e;
  for (int k = 0; k < 10; ++k) {
    const int i = LC::kRow[k], j = LC::kCol[k];
    e(k) = j == 3 ? (i == 3 ? mass : h(i)) : sigma(i, j);
  }
  return e;
}

template <typename Scalar>
PseudoInertiaTpl<Scalar> PseudoInertiaTpl<Scalar>::FromEntries(const Vector10& e) {
  using LC = LogCholeskyParametersTpl<Scalar>;
  PseudoInertiaTpl j;
  for (int k = 0; k < 10; ++k) {
    const int r = LC::kRow[k], c = LC::kCol[k];
    if (c == 3) {
      (r == 3 ? j.mass : j.h(r)) = e(k);
    } else {
      j.sigma(r, c) = j.sigma(c, r) = e(k);
    }
  }
  return j;
}

using PseudoInertiaD = PseudoInertiaTpl<double>;
using LogCholeskyParameters = LogCholeskyParametersTpl<double>;

}  // namespace tactforce::inertia
