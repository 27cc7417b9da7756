// BASELINE_LS: Atkeson, An & Hollerbach 1986.
#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "absl/strings/str_cat.h"
#include "internal.h"

namespace tactforce::inertia::internal {

Matrix10d ScaledPseudoInverse(const Matrix10d& A, const Vector10d& scale, double relative_tolerance) {
  const Matrix10d S = scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Matrix10d> es(S * A * S);
  Matrix10d pinv = Matrix10d::Zero();
  const double top = es.eigenvalues()(9);
  for (int i = 0; i < 10; ++i) {
    const double l = es.eigenvalues()(i);
    if (l > relative_tolerance * top) pinv += es.eigenvectors().col(i) * es.eigenvectors().col(i).transpose() / l;
  }
  return S * pinv * S;
}

Vector10d ScaledLeastSquares(const Eigen::MatrixXd& Y, const Eigen::VectorXd& b, const Vector10d& scale,
                             int* rank) {
  const Eigen::MatrixXd Ys = Y * scale.asDiagonal();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(Ys, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const Eigen::VectorXd sv = svd.singularValues();
  const double tol = 1e-10 * (sv.size() ? sv(0) : 0.0);
  Eigen::VectorXd utb = svd.matrixU().transpose() * b;
  int r = 0;
  for (int i = 0; i < sv.size(); ++i) {
    if (sv(i) > tol) {
      utb(i) /= sv(i);
      ++r;
    } else {
      utb(i) = 0;
    }
  }
  if (rank) *rank = r;
  const Vector10d x = svd.matrixV() * utb;
  return scale.cwiseProduct(x);
}

absl::StatusOr<MethodOutput> FitBaselineLs(const InertiaSamples& s, const InertiaOptions& o) {
  MethodOutput out;
  std::vector<KinPoint> kin =
      s.HasKinematics() ? MeasuredKinematicsPoints(s, o.gravity) : FiniteDifferenceKinematics(s, o.gravity);
  out.notes.push_back(s.HasKinematics() ? "kinematics: measured columns"
                                        : "kinematics: three-point finite differences of the poses");
  if (o.prior) out.notes.push_back("prior ignored by baseline-ls");
  if (!o.hull.empty()) out.notes.push_back("hull ignored by baseline-ls");
  const int n = static_cast<int>(kin.size());
  std::vector<Vector6d> wrench(n);
  for (int i = 0; i < n; ++i) wrench[i] = SampleWrench(s.samples[kin[i].index], s.source);

  if (o.savitzky_golay && n >= 5) {
    const int window = std::min(o.savitzky_golay_window, n % 2 ? n : n - 1);
    std::vector<double> t(n);
    Eigen::MatrixXd m(n, 15);
    for (int i = 0; i < n; ++i) {
      t[i] = kin[i].t;
      m.row(i) << kin[i].w.transpose(), kin[i].dw.transpose(), kin[i].a_minus_g.transpose(),
          wrench[i].transpose();
    }
    const Eigen::MatrixXd f = SmoothSeries(t, m, window, 3);
    for (int i = 0; i < n; ++i) {
      kin[i].w = f.row(i).segment<3>(0).transpose();
      kin[i].dw = f.row(i).segment<3>(3).transpose();
      kin[i].a_minus_g = f.row(i).segment<3>(6).transpose();
      wrench[i] = f.row(i).segment<6>(9).transpose();
    }
    out.notes.push_back(absl::StrCat("Savitzky-Golay smoothing: cubic, window ", window));
  }

  Eigen::MatrixXd Y(6 * n, 10);
  Eigen::VectorXd b(6 * n);
  for (int i = 0; i < n; ++i) {
    Y.middleRows<6>(6 * i) = Regressor(kin[i].w, kin[i].dw, kin[i].a_minus_g);
    b.segment<6>(6 * i) = wrench[i];
  }
  int rank = 0;
  Vector10d pi = ScaledLeastSquares(Y, b, Vector10d::Ones(), &rank);
  double m0 = 1, len = 0.1;
  RoughScale(pi, nullptr, &m0, &len);
  out.scale = ParameterScale(m0, len);
  pi = ScaledLeastSquares(Y, b, out.scale, &rank);
  out.pi = pi;
  out.iterations = 1;
  out.samples_used = n;
  ResidualRms(kin, wrench, pi, &out.rms_force, &out.rms_torque);

  // OLS covariance sigma^2 (Y^T Y)^+ and a whitened information matrix for
  // the excitation analysis (force rows / rms_force, torque rows / rms_torque).
  const Eigen::VectorXd r = Y * pi - b;
  const double dof = std::max(1, 6 * n - rank);
  const double s2 = r.squaredNorm() / dof;
  const Matrix10d YtY = Y.transpose() * Y;
  out.cov = s2 * ScaledPseudoInverse(YtY, out.scale, 1e-20);
  const double wf = 1.0 / std::max(out.rms_force * out.rms_force, 1e-300);
  const double wt = 1.0 / std::max(out.rms_torque * out.rms_torque, 1e-300);
  const double scale_t = std::isfinite(wt / wf) && out.rms_force > 0 && out.rms_torque > 0 ? wt / wf : 1.0 / (len * len);
  Matrix10d info = Matrix10d::Zero();
  for (int i = 0; i < n; ++i) {
    const Matrix6x10 Yi = Y.middleRows<6>(6 * i);
    info += Yi.topRows<3>().transpose() * Yi.topRows<3>() + scale_t * Yi.bottomRows<3>().transpose() * Yi.bottomRows<3>();
  }
  out.info = info;
  if (o.progress) o.progress(0.9);
  return out;
}

}  // namespace tactforce::inertia::internal
