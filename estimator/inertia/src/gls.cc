// The generalised least squares shared by CONSTRAINED and DENSITY (gls.h).
#include "gls.h"

#include <algorithm>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>

namespace tactforce::inertia::internal {

GlsData PrepareGls(const InertiaSamples& s, const InertiaOptions& o,
                   std::vector<std::string>* notes, InterruptPoll* poll) {
  GlsData d;
  d.kin = SmoothedKinematics(s, o.gravity, o.noise, o.smoothing_window, notes, poll);
  if (poll->stopped()) return d;
  const int n = static_cast<int>(d.kin.size());
  d.wrench.resize(n);
  d.wcov.resize(n);
  d.Y.resize(n);
  double f2 = 0, t2 = 0;
  for (int k = 0; k < n; ++k) {
    if (poll->Tick()) return d;
    const InertiaSample& x = s.samples[d.kin[k].index];
    d.wrench[k] = SampleWrench(x, s.source);
    d.known = WrenchCovariance(x, s.source, o.noise, &d.wcov[k]) && d.known;
    d.Y[k] = Regressor(d.kin[k].w, d.kin[k].dw, d.kin[k].a_minus_g);
    f2 += d.wrench[k].head<3>().squaredNorm();
    t2 += d.wrench[k].tail<3>().squaredNorm();
  }
  notes->push_back(d.known ? "wrench noise: from the given sigmas"
                           : "wrench noise: estimated from residuals");
  // Floors keep the weights finite on noise-free data.
  d.floor_f = 1e-18 * std::max(f2 / (3.0 * n), 1e-300);
  d.floor_t = 1e-18 * std::max(t2 / (3.0 * n), 1e-300);
  for (int k = 0; k < n; ++k) {
    if (poll->Tick()) return d;
    d.YtY += d.Y[k].transpose() * d.Y[k];
    d.Ytb += d.Y[k].transpose() * d.wrench[k];
  }
  return d;
}

void AccumulateGls(const GlsData& d, const Vector10d& pi, InterruptPoll* poll, GlsSums* total,
                   int blocks, std::vector<GlsSums>* per_block, std::vector<Matrix6d>* whiteners) {
  const int n = static_cast<int>(d.kin.size());
  Matrix6x10 unit_a[3], unit_dw[3];  // d Y / d(a - g), d Y / d dw (constant)
  for (int j = 0; j < 3; ++j) {
    unit_a[j] = Regressor(Vec3::Zero(), Vec3::Zero(), Vec3::Unit(j));
    unit_dw[j] = Regressor(Vec3::Zero(), Vec3::Unit(j), Vec3::Zero());
  }
  // Residual covariance per sample.
  Matrix6d est = Matrix6d::Zero();
  if (!d.known) {
    for (int k = 0; k < n; ++k) {
      if (poll->Tick()) return;
      const Vector6d r = d.Y[k] * pi - d.wrench[k];
      est += r * r.transpose();
    }
    est /= std::max(1, n - 2);
  }
  const InertialParameters cur = InertialParameters::FromStandard(pi);
  const Eigen::Matrix3d Io = cur.InertiaOrigin();
  const Vec3 h = pi.segment<3>(1);
  *total = GlsSums();
  if (per_block) per_block->assign(blocks, GlsSums());
  if (whiteners) whiteners->resize(n);
  Matrix10d& A = total->A;
  Vector10d& bvec = total->b;
  Matrix10d& bias = total->bias;
  for (int k = 0; k < n; ++k) {
    if (poll->Tick(4)) return;
    Matrix6d C = d.known ? d.wcov[k] : est;
    const KinPoint& q = d.kin[k];
    // Kinematic errors propagated through the model at the current pi.
    Eigen::Matrix<double, 6, 3> Ja, Jw, Jdw, Jr;
    Ja << pi(0) * Eigen::Matrix3d::Identity(), Skew(h);
    Jw << -Skew(q.w.cross(h)) - Skew(q.w) * Skew(h), -Skew(Io * q.w) + Skew(q.w) * Io;
    Jdw << -Skew(h), Io;
    Jr = Ja * Skew(q.a_minus_g);
    Matrix6d Ck = q.var_a * Ja * Ja.transpose() + q.var_w * Jw * Jw.transpose() +
                  q.var_dw * Jdw * Jdw.transpose() + q.var_rot * Jr * Jr.transpose();
    if (d.known) C += Ck;
    C.diagonal().head<3>().array() += d.floor_f;
    C.diagonal().tail<3>().array() += d.floor_t;
    const Eigen::LLT<Matrix6d> llt(C);
    const Matrix6d W = llt.matrixL().solve(Matrix6d::Identity());  // W^T W = C^-1
    const Matrix6x10 WY = W.lazyProduct(d.Y[k]);
    const Vector6d Ww = W * d.wrench[k];
    A.noalias() += WY.transpose().lazyProduct(WY);
    bvec.noalias() += WY.transpose() * Ww;
    total->c += Ww.squaredNorm();
    ++total->count;
    GlsSums* blk = per_block ? &(*per_block)[BlockOf(k, n, blocks)] : nullptr;
    if (blk) {
      blk->A.noalias() += WY.transpose().lazyProduct(WY);
      blk->b.noalias() += WY.transpose() * Ww;
      blk->c += Ww.squaredNorm();
      ++blk->count;
    }
    if (whiteners) (*whiteners)[k] = W;
    // Errors-in-variables bias of Y^T W Y: E[dY^T W dY] (first order).
    auto add_bias = [&](double var, const Matrix6x10& D) {
      const Matrix6x10 WD = W.lazyProduct(D);
      bias.noalias() += var * WD.transpose().lazyProduct(WD);
      if (blk) blk->bias.noalias() += var * WD.transpose().lazyProduct(WD);
    };
    for (int j = 0; j < 3; ++j) {
      const Vec3 e = Vec3::Unit(j);
      if (q.var_a > 0) add_bias(q.var_a, unit_a[j]);
      if (q.var_dw > 0) add_bias(q.var_dw, unit_dw[j]);
      if (q.var_rot > 0)
        add_bias(q.var_rot, Regressor(Vec3::Zero(), Vec3::Zero(), Skew(q.a_minus_g) * e));
      if (q.var_w > 0) {
        const double eps = 1e-4 * std::max(1.0, q.w.norm());
        add_bias(q.var_w, (Regressor(q.w + eps * e, Vec3::Zero(), Vec3::Zero()) -
                           Regressor(q.w - eps * e, Vec3::Zero(), Vec3::Zero())) /
                              (2 * eps));
      }
    }
  }
}

Matrix10d BiasCorrected(const GlsSums& sums, const Vector10d& scale, bool* applied) {
  *applied = false;
  if (!(sums.bias.norm() > 0)) return sums.A;
  const Matrix10d S = scale.asDiagonal();
  Eigen::SelfAdjointEigenSolver<Matrix10d> e1(S * sums.A * S, Eigen::EigenvaluesOnly);
  Eigen::SelfAdjointEigenSolver<Matrix10d> e2(S * (sums.A - sums.bias) * S, Eigen::EigenvaluesOnly);
  if (e2.eigenvalues()(0) > 0.5 * e1.eigenvalues()(0)) {
    *applied = true;
    return sums.A - sums.bias;
  }
  return sums.A;
}

}  // namespace tactforce::inertia::internal
