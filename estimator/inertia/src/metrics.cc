// Metrics on inertial parameters (metrics.h): the pseudo-inertia and its
// consistency test, the paper's error (eq. 38), the Riemannian distance,
// the comparison against a truth, principal axes and the equivalent box.
#include "tactforce/inertia/metrics.h"

#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

#include "tactforce/inertia/pseudo_inertia.h"

namespace tactforce::inertia {

Eigen::Matrix4d PseudoInertia(const InertialParameters& p) {
  return PseudoInertiaD::FromParameters(p).Matrix();
}

InertialParameters FromPseudoInertia(const Eigen::Matrix4d& P) {
  return PseudoInertiaD::FromMatrix(Eigen::Matrix4d(0.5 * (P + P.transpose()))).Parameters();
}

double ScaledPseudoInertiaMinEigenvalue(const InertialParameters& p) {
  const Eigen::Matrix4d P = PseudoInertia(p);
  if (!(p.mass > 0.0) || !P.allFinite()) return -std::numeric_limits<double>::infinity();
  const double s2 = P.topLeftCorner<3, 3>().trace() / p.mass;
  const double s = s2 > 0 ? std::sqrt(s2) : 1.0;
  Eigen::Vector4d d(1 / (s * std::sqrt(p.mass)), 1 / (s * std::sqrt(p.mass)),
                    1 / (s * std::sqrt(p.mass)), 1 / std::sqrt(p.mass));
  const Eigen::Matrix4d Ps = d.asDiagonal() * P * d.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(Ps, Eigen::EigenvaluesOnly);
  return es.eigenvalues()(0);
}

bool IsPhysicallyConsistent(const InertialParameters& p, double tolerance) {
  return ScaledPseudoInertiaMinEigenvalue(p) > tolerance;
}

double PaperInertialError(const Eigen::Matrix4d& p_gt, const Eigen::Matrix4d& p_est) {
  const Eigen::Matrix4d x = p_gt.ldlt().solve(p_est);
  return std::abs(4.0 - x.trace());
}

double RiemannianDistance(const Eigen::Matrix4d& p_gt, const Eigen::Matrix4d& p_est) {
  // Generalised eigenvalues of (P_est, P_gt): symmetric-definite problem.
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix4d> es(p_est, p_gt, Eigen::EigenvaluesOnly);
  if (es.info() != Eigen::Success) return std::numeric_limits<double>::infinity();
  double sum = 0.0;
  for (int i = 0; i < 4; ++i) {
    const double l = es.eigenvalues()(i);
    if (!(l > 0.0)) return std::numeric_limits<double>::infinity();
    sum += std::log(l) * std::log(l);
  }
  return std::sqrt(sum);
}

InertiaErrors CompareInertia(const InertialParameters& truth, const InertialParameters& est) {
  InertiaErrors e;
  const Eigen::Matrix4d pg = PseudoInertia(truth), pe = PseudoInertia(est);
  e.paper_metric = PaperInertialError(pg, pe);
  e.riemannian = RiemannianDistance(pg, pe);
  e.mass_percent = 100.0 * std::abs(est.mass - truth.mass) / std::abs(truth.mass);
  e.com_mm = 1000.0 * (est.com - truth.com).norm();
  e.consistent = IsPhysicallyConsistent(est);
  return e;
}

void PrincipalAxes(const InertiaTensor& inertia, Vec3* moments, Eigen::Matrix3d* axes) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(inertia.Matrix());
  Eigen::Matrix3d v = es.eigenvectors();
  if (v.determinant() < 0) v.col(2) = -v.col(2);
  if (moments) *moments = es.eigenvalues();
  if (axes) *axes = v;
}

double EquivalentBoxSize(const InertialParameters& p) {
  if (!(p.mass > 0)) return 0.0;
  const Eigen::Matrix3d h = p.inertia_com.Matrix();
  const Eigen::Matrix3d sigma = 0.5 * h.trace() * Eigen::Matrix3d::Identity() - h;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sigma, Eigen::EigenvaluesOnly);
  const double smax = es.eigenvalues()(2);
  if (!(smax > 0)) return 0.0;
  return 2.0 * std::sqrt(3.0 * smax / p.mass);
}

}  // namespace tactforce::inertia
