// Error metrics for inertial estimates.
//
//   pseudo-inertia (paper eq. 21, second moment about the object origin):
//     P = [[ 1/2 Tr(H_o) I - H_o , m c ], [ m c^T , m ]],  H_o = inertia about the origin
//   paper metric (eq. 38):  |4 - Tr(P_gt^-1 P_est)|
//   Riemannian distance (Lee & Park):  sqrt(sum_i log^2 lambda_i(P_gt^-1 P_est))
//     (+infinity when P_est is not positive definite: it is off the manifold)
// The paper's metric is zero whenever the eigenvalues of P_gt^-1 P_est sum to
// 4, e.g. (2, 0.5, 0.5, 1): an estimate can be wrong with metric 0.
#pragma once

#include <Eigen/Core>

#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

// PseudoInertiaD::FromParameters(p).Matrix() (pseudo_inertia.h).
Eigen::Matrix4d PseudoInertia(const InertialParameters& p);
// Inverse of PseudoInertia from the symmetric part of P (P need not be
// positive definite).
InertialParameters FromPseudoInertia(const Eigen::Matrix4d& P);

// Positive definite (Cholesky succeeds and the smallest eigenvalue of P
// scaled to unit mass and unit size exceeds `tolerance`).
bool IsPhysicallyConsistent(const InertialParameters& p, double tolerance = 1e-12);
// Smallest eigenvalue of D P D with D = diag(1/(s sqrt m) x3, 1/sqrt m),
// s^2 = Tr(second moment)/m: scale-free; <= 0 means inconsistent.
double ScaledPseudoInertiaMinEigenvalue(const InertialParameters& p);

double PaperInertialError(const Eigen::Matrix4d& p_gt, const Eigen::Matrix4d& p_est);
double RiemannianDistance(const Eigen::Matrix4d& p_gt, const Eigen::Matrix4d& p_est);

struct InertiaErrors {
  double paper_metric = 0.0;  // |4 - Tr(P_gt^-1 P_est)|
  double riemannian = 0.0;    // affine-invariant distance (inf if inconsistent)
  double mass_percent = 0.0;  // 100 |m_est - m_gt| / m_gt
  double com_mm = 0.0;        // 1000 |c_est - c_gt|
  bool consistent = false;    // estimate's pseudo-inertia positive definite
};

InertiaErrors CompareInertia(const InertialParameters& truth, const InertialParameters& estimate);

// Principal moments (ascending) and axes (columns, right-handed) of the
// inertia about the CoM.
void PrincipalAxes(const InertiaTensor& inertia, Vec3* moments, Eigen::Matrix3d* axes);

// Size (m) of the uniform box with the same second moments about the CoM:
// its longest edge, 2 sqrt(3 sigma_max / m). Used for "CoM error % of size"
// when no geometry is known. 0 if inconsistent.
double EquivalentBoxSize(const InertialParameters& p);

}  // namespace tactforce::inertia
