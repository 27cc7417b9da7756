// BASELINE_LS: Atkeson, An & Hollerbach 1986.
#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <Eigen/SVD>

#include "absl/strings/str_cat.h"
#include "internal.h"

namespace tactforce::inertia::internal {

absl::Status Interrupted() { return absl::CancelledError("interrupted"); }

Matrix10d ScaledPseudoInverse(const Matrix10d& A, const Vector10d& scale,
                              double relative_tolerance) {
  const Matrix10d S = scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Matrix10d> es(S * A * S);
  Matrix10d pinv = Matrix10d::Zero();
  const double top = es.eigenvalues()(9);
  for (int i = 0; i < 10; ++i) {
    const double l = es.eigenvalues()(i);
    if (l > relative_tolerance * top)
      pinv += es.eigenvectors().col(i) * es.eigenvectors().col(i).transpose() / l;
  }
  return S * pinv * S;
}

StackedLeastSquares::StackedLeastSquares(int cols)
    : cols_(cols),
      buffer_(kChunkRows + cols + 1, cols + 1),
      triangle_(Eigen::MatrixXd::Zero(cols + 1, cols + 1)) {}

void StackedLeastSquares::Add(const Eigen::Ref<const Eigen::MatrixXd>& Y,
                              const Eigen::Ref<const Eigen::VectorXd>& b) {
  for (Eigen::Index done = 0; done < Y.rows();) {
    const Eigen::Index take = std::min<Eigen::Index>(Y.rows() - done, kChunkRows - rows_);
    buffer_.block(cols_ + 1 + rows_, 0, take, cols_) = Y.middleRows(done, take);
    buffer_.block(cols_ + 1 + rows_, cols_, take, 1) = b.segment(done, take);
    rows_ += static_cast<int>(take);
    done += take;
    if (rows_ == kChunkRows) Flush();
  }
}

// Householder QR of [triangle; buffered rows]: its R is the new triangle.
void StackedLeastSquares::Flush() {
  if (rows_ == 0) return;
  buffer_.topRows(cols_ + 1) = triangle_;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(buffer_.topRows(cols_ + 1 + rows_));
  triangle_ = qr.matrixQR().topRows(cols_ + 1).triangularView<Eigen::Upper>();
  rows_ = 0;
}

const Eigen::MatrixXd& StackedLeastSquares::Triangle() {
  Flush();
  return triangle_;
}

Vector10d ScaledLeastSquares(const Eigen::MatrixXd& triangle, const Vector10d& scale, int* rank) {
  // Y S = Q (R S): the singular values and right vectors of R S are those of Y S.
  const Matrix10d Rs = triangle.topLeftCorner<10, 10>() * scale.asDiagonal();
  Eigen::JacobiSVD<Matrix10d> svd(Rs, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Vector10d sv = svd.singularValues();
  const double tol = 1e-10 * sv(0);
  Vector10d utb = svd.matrixU().transpose() * triangle.col(10).head<10>();
  int r = 0;
  for (int i = 0; i < 10; ++i) {
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

namespace {

// Savitzky-Golay smoothing (cubic) of the kinematics and wrenches in place.
void SmoothInPlace(int window, std::vector<KinPoint>* kin, std::vector<Vector6d>* wrench,
                   InterruptPoll* poll) {
  const int n = static_cast<int>(kin->size());
  std::vector<double> t(n);
  Eigen::MatrixXd m(n, 15);
  for (int i = 0; i < n; ++i) {
    if (poll->Tick()) return;
    const KinPoint& q = (*kin)[i];
    t[i] = q.t;
    m.row(i) << q.w.transpose(), q.dw.transpose(), q.a_minus_g.transpose(),
        (*wrench)[i].transpose();
  }
  const Eigen::MatrixXd f = SmoothSeries(t, m, window, 3, poll);
  for (int i = 0; i < n; ++i) {
    if (poll->Tick()) return;
    KinPoint& q = (*kin)[i];
    q.w = f.row(i).segment<3>(0).transpose();
    q.dw = f.row(i).segment<3>(3).transpose();
    q.a_minus_g = f.row(i).segment<3>(6).transpose();
    (*wrench)[i] = f.row(i).segment<6>(9).transpose();
  }
}

// The stacked QR triangle of the regressor rows and wrenches.
Eigen::MatrixXd RegressorTriangle(const std::vector<KinPoint>& kin,
                                  const std::vector<Vector6d>& wrench, InterruptPoll* poll) {
  StackedLeastSquares ls(10);
  for (size_t i = 0; i < kin.size(); ++i) {
    if (poll->Tick()) break;
    ls.Add(Regressor(kin[i].w, kin[i].dw, kin[i].a_minus_g), wrench[i]);
  }
  return ls.Triangle();
}

// Information matrix for the excitation analysis: force rows / rms_force,
// torque rows / rms_torque (scale_t = their relative weight).
Matrix10d WhitenedInformation(const std::vector<KinPoint>& kin, double scale_t,
                              InterruptPoll* poll) {
  Matrix10d info = Matrix10d::Zero();
  for (const KinPoint& q : kin) {
    if (poll->Tick()) break;
    const Matrix6x10 Yi = Regressor(q.w, q.dw, q.a_minus_g);
    info += Yi.topRows<3>().transpose() * Yi.topRows<3>() +
            scale_t * Yi.bottomRows<3>().transpose() * Yi.bottomRows<3>();
  }
  return info;
}

}  // namespace

absl::StatusOr<MethodOutput> FitBaselineLs(const InertiaSamples& s, const InertiaOptions& o) {
  InterruptPoll poll(o.interrupt);
  MethodOutput out;
  std::vector<KinPoint> kin = s.HasKinematics() ? MeasuredKinematicsPoints(s, o.gravity, &poll)
                                                : FiniteDifferenceKinematics(s, o.gravity, &poll);
  out.notes.push_back(s.HasKinematics()
                          ? "kinematics: measured columns"
                          : "kinematics: three-point finite differences of the poses");
  if (o.prior) out.notes.push_back("prior ignored by baseline-ls");
  if (!o.hull.empty()) out.notes.push_back("hull ignored by baseline-ls");
  const int n = static_cast<int>(kin.size());
  std::vector<Vector6d> wrench(n);
  for (int i = 0; i < n && !poll.Tick(); ++i)
    wrench[i] = SampleWrench(s.samples[kin[i].index], s.source);
  if (poll.stopped()) return Interrupted();

  if (o.baseline_ls.savitzky_golay && n >= 5) {
    const int window = std::min(o.baseline_ls.savitzky_golay_window, n % 2 ? n : n - 1);
    SmoothInPlace(window, &kin, &wrench, &poll);
    if (poll.stopped()) return Interrupted();
    out.notes.push_back(absl::StrCat("Savitzky-Golay smoothing: cubic, window ", window));
  }

  const Eigen::MatrixXd triangle = RegressorTriangle(kin, wrench, &poll);
  if (poll.stopped()) return Interrupted();
  int rank = 0;
  Vector10d pi = ScaledLeastSquares(triangle, Vector10d::Ones(), &rank);
  double m0 = 1, len = 0.1;
  RoughScale(pi, nullptr, &m0, &len);
  out.scale = ParameterScale(m0, len);
  pi = ScaledLeastSquares(triangle, out.scale, &rank);
  out.pi = pi;
  out.iterations = 1;
  out.samples_used = n;
  ResidualRms(kin, wrench, pi, &poll, &out.rms_force, &out.rms_torque);

  // OLS covariance sigma^2 (Y^T Y)^+ (Y^T Y = R^T R) and a whitened
  // information matrix for the excitation analysis.
  const double dof = std::max(1, 6 * n - rank);
  const double s2 =
      3.0 * n * (out.rms_force * out.rms_force + out.rms_torque * out.rms_torque) / dof;
  const Matrix10d R = triangle.topLeftCorner<10, 10>();
  out.cov = s2 * ScaledPseudoInverse(R.transpose() * R, out.scale, 1e-20);
  const double wf = 1.0 / std::max(out.rms_force * out.rms_force, 1e-300);
  const double wt = 1.0 / std::max(out.rms_torque * out.rms_torque, 1e-300);
  const double scale_t = std::isfinite(wt / wf) && out.rms_force > 0 && out.rms_torque > 0
                             ? wt / wf
                             : 1.0 / (len * len);
  out.info = WhitenedInformation(kin, scale_t, &poll);
  if (poll.stopped()) return Interrupted();
  if (o.progress) o.progress(0.9);
  return out;
}

}  // namespace tactforce::inertia::internal
