// CONSTRAINED: physically consistent by construction (log-Cholesky
// coordinates of the pseudo-inertia, Rucker & Wensing 2022), generalised
// least squares with errors in forces and kinematics, CoM-in-hull rows.
#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <nlopt.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "internal.h"
#include "tactforce/inertia/metrics.h"

namespace tactforce::inertia::internal {
namespace {

// Index maps: U (upper triangular, 4x4) entries <-> theta, P entries <-> p.
constexpr int kUr[10] = {0, 1, 2, 3, 0, 0, 0, 1, 1, 2};
constexpr int kUc[10] = {0, 1, 2, 3, 1, 2, 3, 2, 3, 3};
constexpr int kPi[10] = {0, 1, 2, 3, 0, 0, 0, 1, 1, 2};
constexpr int kPj[10] = {0, 1, 2, 3, 1, 2, 3, 2, 3, 3};

Eigen::Matrix4d UFromTheta(const Vector10d& th) {
  Eigen::Matrix4d U = Eigen::Matrix4d::Zero();
  for (int a = 0; a < 10; ++a) U(kUr[a], kUc[a]) = a < 4 ? std::exp(th(a)) : th(a);
  return U;
}

Vector10d PVec(const Eigen::Matrix4d& P) {
  Vector10d p;
  for (int k = 0; k < 10; ++k) p(k) = P(kPi[k], kPj[k]);
  return p;
}

// The quadratic model in scaled pseudo-inertia entries p:
//   f = 1/2 p^T A p - b^T p + w (q^T p - log det P)   (+ const)
struct Model {
  Matrix10d A;
  Vector10d b;
  double w = 0;                 // prior weight
  Vector10d q = Vector10d::Zero();
  double scale = 1.0;           // objective divisor (conditioning)
  std::vector<Vector10d> rows;  // hull rows a^T p <= 0

  double F(const Vector10d& th) const {
    const Eigen::Matrix4d U = UFromTheta(th);
    const Vector10d p = PVec(U * U.transpose());
    double f = 0.5 * p.dot(A * p) - b.dot(p);
    if (w > 0) f += w * (q.dot(p) - 2.0 * th.head<4>().sum());
    return f / scale;
  }

  // Value, gradient and exact Hessian in theta.
  double Eval(const Vector10d& th, Vector10d* g, Matrix10d* H) const {
    const Eigen::Matrix4d U = UFromTheta(th);
    const Vector10d p = PVec(U * U.transpose());
    const Matrix10d J = Jacobian(th, U);
    const Vector10d gp = A * p - b + w * q;
    double f = 0.5 * p.dot(A * p) - b.dot(p);
    if (w > 0) f += w * (q.dot(p) - 2.0 * th.head<4>().sum());
    Vector10d grad = J.transpose() * gp;
    if (w > 0) grad.head<4>().array() -= 2.0 * w;
    if (g) *g = grad / scale;
    if (H) {
      // Gamma: tr(Gamma P) = gp . p.
      Eigen::Matrix4d Gm = Eigen::Matrix4d::Zero();
      for (int k = 0; k < 10; ++k) {
        if (kPi[k] == kPj[k]) Gm(kPi[k], kPi[k]) = gp(k);
        else Gm(kPi[k], kPj[k]) = Gm(kPj[k], kPi[k]) = 0.5 * gp(k);
      }
      const Eigen::Matrix4d GU = Gm * U;
      Matrix10d Hs = J.transpose() * A * J;
      for (int a = 0; a < 10; ++a) {
        const double da = a < 4 ? U(kUr[a], kUc[a]) : 1.0;
        for (int c = 0; c < 10; ++c) {
          if (kUc[a] != kUc[c]) continue;
          const double dc = c < 4 ? U(kUr[c], kUc[c]) : 1.0;
          Hs(a, c) += 2.0 * Gm(kUr[a], kUr[c]) * da * dc;
        }
        if (a < 4) Hs(a, a) += 2.0 * GU(kUr[a], kUc[a]) * U(kUr[a], kUc[a]);
      }
      *H = 0.5 * (Hs + Hs.transpose()) / scale;
    }
    return f / scale;
  }

  static Matrix10d Jacobian(const Vector10d& th, const Eigen::Matrix4d& U) {
    Matrix10d J = Matrix10d::Zero();
    for (int k = 0; k < 10; ++k) {
      const int i = kPi[k], j = kPj[k];
      for (int a = 0; a < 10; ++a) {
        const int r = kUr[a], c = kUc[a];
        double d = 0;
        if (i == r) d += U(j, c);
        if (j == r) d += U(i, c);
        J(k, a) = d * (a < 4 ? U(r, c) : 1.0);
      }
    }
    return J;
  }
};

Vector10d ThetaFromP(const Eigen::Matrix4d& Pin) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(0.5 * (Pin + Pin.transpose()));
  Eigen::Vector4d l = es.eigenvalues();
  const double top = std::max(l(3), 1e-12);
  for (int i = 0; i < 4; ++i) l(i) = std::max(l(i), 1e-3 * top);
  const Eigen::Matrix4d P = es.eigenvectors() * l.asDiagonal() * es.eigenvectors().transpose();
  // P = U U^T with U upper triangular: Cholesky of the index-reversed matrix.
  Eigen::Matrix4d X = P.reverse();
  Eigen::LLT<Eigen::Matrix4d> llt(0.5 * (X + X.transpose()));
  const Eigen::Matrix4d L = llt.matrixL();
  const Eigen::Matrix4d U = L.reverse();
  Vector10d th;
  for (int a = 0; a < 10; ++a) th(a) = a < 4 ? std::log(std::max(U(kUr[a], kUc[a]), 1e-300)) : U(kUr[a], kUc[a]);
  return th;
}

// Lower bound on the log-diagonal of U: keeps P strictly positive definite
// (smallest eigenvalue of the scaled P about >= 1e-8) at the boundary.
constexpr double kMinLogDiag = -9.2;  // log(1e-4)

// Damped (projected) Newton on the model.
Vector10d Newton(const Model& m, Vector10d th, int max_iter, int* iterations) {
  Vector10d g;
  Matrix10d H;
  double f = m.Eval(th, &g, &H);
  double lambda = 1e-8;
  int it = 0;
  for (; it < max_iter; ++it) {
    bool accepted = false;
    for (int tries = 0; tries < 40 && !accepted; ++tries) {
      Matrix10d Hd = H;
      Hd.diagonal().array() += lambda * std::max(1.0, H.diagonal().cwiseAbs().maxCoeff());
      Eigen::LDLT<Matrix10d> ldlt(Hd);
      if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) {
        lambda = std::max(lambda * 10, 1e-8);
        continue;
      }
      Vector10d step = -ldlt.solve(g);
      if (!step.allFinite()) {
        lambda = std::max(lambda * 10, 1e-8);
        continue;
      }
      // Keep the log-diagonal steps moderate.
      const double mx = step.head<4>().cwiseAbs().maxCoeff();
      if (mx > 2.0) step *= 2.0 / mx;
      Vector10d cand = th + step;
      for (int i = 0; i < 4; ++i) cand(i) = std::max(cand(i), kMinLogDiag);
      step = cand - th;
      const double fc = m.F(cand);
      if (std::isfinite(fc) && fc <= f) {
        const double dec = f - fc;
        th = cand;
        f = m.Eval(th, &g, &H);
        lambda = std::max(lambda / 5, 1e-12);
        accepted = true;
        if (step.norm() < 1e-11 || dec <= 1e-16 * std::abs(f)) {
          *iterations += it + 1;
          return th;
        }
      } else {
        lambda = std::max(lambda * 10, 1e-8);
      }
    }
    if (!accepted) break;
  }
  *iterations += it;
  return th;
}

struct SlsqpData {
  const Model* model;
  int evals = 0;
};

double SlsqpObjective(unsigned n, const double* x, double* grad, void* data) {
  auto* d = static_cast<SlsqpData*>(data);
  ++d->evals;
  const Vector10d th = Eigen::Map<const Vector10d>(x);
  Vector10d g;
  const double f = d->model->Eval(th, grad ? &g : nullptr, nullptr);
  if (grad) {
    Eigen::Map<Vector10d> gm(grad);
    gm = g;
  }
  return f;
}

void SlsqpConstraints(unsigned m, double* result, unsigned n, const double* x, double* grad, void* data) {
  auto* d = static_cast<SlsqpData*>(data);
  const Vector10d th = Eigen::Map<const Vector10d>(x);
  const Eigen::Matrix4d U = UFromTheta(th);
  const Vector10d p = PVec(U * U.transpose());
  Matrix10d J;
  if (grad) J = Model::Jacobian(th, U);
  for (unsigned j = 0; j < m; ++j) {
    const Vector10d& a = d->model->rows[j];
    result[j] = a.dot(p);
    if (grad) {
      const Vector10d gj = J.transpose() * a;
      for (unsigned i = 0; i < n; ++i) grad[j * n + i] = gj(i);
    }
  }
}

}  // namespace

GlsData PrepareGls(const InertiaSamples& s, const InertiaOptions& o, std::vector<std::string>* notes) {
  GlsData d;
  d.kin = SmoothedKinematics(s, o.gravity, o.noise, o.smoothing_window, notes);
  const int n = static_cast<int>(d.kin.size());
  d.wrench.resize(n);
  d.wcov.resize(n);
  d.Y.resize(n);
  double f2 = 0, t2 = 0;
  for (int k = 0; k < n; ++k) {
    const InertiaSample& x = s.samples[d.kin[k].index];
    d.wrench[k] = SampleWrench(x, s.source);
    d.known = WrenchCovariance(x, s.source, o.noise, &d.wcov[k]) && d.known;
    d.Y[k] = Regressor(d.kin[k].w, d.kin[k].dw, d.kin[k].a_minus_g);
    f2 += d.wrench[k].head<3>().squaredNorm();
    t2 += d.wrench[k].tail<3>().squaredNorm();
  }
  notes->push_back(d.known ? "wrench noise: from the given sigmas" : "wrench noise: estimated from residuals");
  // Floors keep the weights finite on noise-free data.
  d.floor_f = 1e-18 * std::max(f2 / (3.0 * n), 1e-300);
  d.floor_t = 1e-18 * std::max(t2 / (3.0 * n), 1e-300);
  for (int k = 0; k < n; ++k) {
    d.YtY += d.Y[k].transpose() * d.Y[k];
    d.Ytb += d.Y[k].transpose() * d.wrench[k];
  }
  return d;
}

void AccumulateGls(const GlsData& d, const Vector10d& pi, GlsSums* total, int blocks,
                   std::vector<GlsSums>* per_block, std::vector<Matrix6d>* whiteners) {
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
      if (q.var_rot > 0) add_bias(q.var_rot, Regressor(Vec3::Zero(), Vec3::Zero(), Skew(q.a_minus_g) * e));
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

absl::StatusOr<MethodOutput> FitConstrained(const InertiaSamples& s, const InertiaOptions& o,
                                            const ConvexHull* hull) {
  MethodOutput out;
  const GlsData gls = PrepareGls(s, o, &out.notes);
  const std::vector<KinPoint>& kin = gls.kin;
  const std::vector<Vector6d>& wrench = gls.wrench;
  const int n = static_cast<int>(kin.size());
  const Matrix10d& YtY = gls.YtY;
  const Vector10d& Ytb = gls.Ytb;

  // Unweighted start (normal equations, minimum norm in scaled parameters),
  // then scales.
  auto solve_scaled = [&](const Vector10d& scale) {
    const Matrix10d S = scale.asDiagonal();
    Eigen::SelfAdjointEigenSolver<Matrix10d> es(S * YtY * S);
    const Vector10d r = S * Ytb;
    Vector10d x = Vector10d::Zero();
    const double top = es.eigenvalues()(9);
    for (int i = 0; i < 10; ++i) {
      const double l = es.eigenvalues()(i);
      if (l > 1e-14 * top) x += es.eigenvectors().col(i) * (es.eigenvectors().col(i).dot(r) / l);
    }
    return Vector10d(S * x);
  };
  Vector10d pi = solve_scaled(Vector10d::Ones());
  double m0 = 1, len = 0.1;
  RoughScale(pi, hull, &m0, &len);
  if (o.prior) RoughScale(o.prior->params.ToStandard(), hull, &m0, &len);
  out.scale = ParameterScale(m0, len);
  pi = solve_scaled(out.scale);
  {  // second pass for the scale from a better estimate
    double m1 = m0, l1 = len;
    RoughScale(pi, hull, &m1, &l1);
    if (!o.prior) m0 = m1, len = l1;
    out.scale = ParameterScale(m0, len);
  }

  // Linear map from scaled pseudo-inertia entries p to pi.
  const double dl = 1.0 / (len * std::sqrt(m0)), dm = 1.0 / std::sqrt(m0);
  const Eigen::Vector4d D(dl, dl, dl, dm);
  Matrix10d T = Matrix10d::Zero();  // pi = T p
  auto pidx = [](int i, int j) {
    if (i > j) std::swap(i, j);
    for (int k = 0; k < 10; ++k)
      if (kPi[k] == i && kPj[k] == j) return k;
    return -1;
  };
  auto unscale = [&](int i, int j) { return 1.0 / (D(i) * D(j)); };
  T(0, pidx(3, 3)) = unscale(3, 3);
  for (int i = 0; i < 3; ++i) T(1 + i, pidx(i, 3)) = unscale(i, 3);
  // I_o = tr(Sigma) I - Sigma
  T(4, pidx(1, 1)) = unscale(1, 1), T(4, pidx(2, 2)) = unscale(2, 2);
  T(5, pidx(0, 0)) = unscale(0, 0), T(5, pidx(2, 2)) = unscale(2, 2);
  T(6, pidx(0, 0)) = unscale(0, 0), T(6, pidx(1, 1)) = unscale(1, 1);
  T(7, pidx(0, 1)) = -unscale(0, 1);
  T(8, pidx(0, 2)) = -unscale(0, 2);
  T(9, pidx(1, 2)) = -unscale(1, 2);

  Model model;
  if (o.prior && o.prior->weight > 0) {
    const Eigen::Matrix4d P0 = D.asDiagonal() * PseudoInertia(o.prior->params) * D.asDiagonal();
    const Eigen::Matrix4d G = P0.inverse();
    for (int k = 0; k < 10; ++k) model.q(k) = kPi[k] == kPj[k] ? G(kPi[k], kPi[k]) : 2.0 * G(kPi[k], kPj[k]);
    model.w = o.prior->weight;
  }
  if (hull) {
    for (size_t j = 0; j < hull->normals.size(); ++j) {
      Vector10d a = Vector10d::Zero();
      for (int i = 0; i < 3; ++i) a(pidx(i, 3)) = hull->normals[j](i);
      a(pidx(3, 3)) = -hull->offsets[j] / len;
      // a^T p = (n.h - d m) * dm^2 / len with h, m unscaled: <= 0 inside.
      model.rows.push_back(a);
    }
  }

  Vector10d theta;
  bool have_theta = false;
  Matrix10d A = Matrix10d::Zero();
  for (int round = 0; round < o.reweighting_rounds; ++round) {
    if (o.interrupt && o.interrupt()) return absl::CancelledError("interrupted");
    GlsSums sums;
    AccumulateGls(gls, pi, &sums);
    A = sums.A;
    const Vector10d& bvec = sums.b;
    // Subtract the bias when the corrected matrix stays well positive definite.
    bool corrected = false;
    const Matrix10d Ause = BiasCorrected(sums, out.scale, &corrected);
    if (corrected && round == o.reweighting_rounds - 1) out.notes.push_back("errors-in-variables bias correction applied");
    model.A = T.transpose() * Ause * T;
    model.b = T.transpose() * bvec;
    model.scale = std::max(model.A.diagonal().cwiseAbs().maxCoeff(), 1e-300);
    if (!have_theta) {
      // Unconstrained GLS estimate, projected into the positive definite cone.
      Eigen::SelfAdjointEigenSolver<Matrix10d> es(model.A);
      Vector10d p = Vector10d::Zero();
      const double top = es.eigenvalues()(9);
      for (int i = 0; i < 10; ++i) {
        const double l = es.eigenvalues()(i);
        if (l > 1e-14 * top) p += es.eigenvectors().col(i) * (es.eigenvectors().col(i).dot(model.b) / l);
      }
      Eigen::Matrix4d Pt = Eigen::Matrix4d::Zero();
      for (int k = 0; k < 10; ++k) Pt(kPi[k], kPj[k]) = Pt(kPj[k], kPi[k]) = p(k);
      if (o.prior) Pt = 0.5 * Pt + 0.5 * D.asDiagonal() * PseudoInertia(o.prior->params) * D.asDiagonal();
      if (!o.prior && o.regularization > 0) {
        // Weak entropic regulariser towards an isotropic guess (scaled units).
        const Eigen::Matrix4d Pu = D.asDiagonal().inverse() * Pt * D.asDiagonal().inverse();
        double mg = Pu(3, 3) > 0 && std::isfinite(Pu(3, 3)) ? Pu(3, 3) : m0;
        Vec3 cg = Pu.topRightCorner<3, 1>() / mg;
        if (!cg.allFinite()) cg.setZero();
        if (hull && !hull->Contains(cg, 1e-9)) {
          cg.setZero();
          for (const Vec3& v : hull->vertices) cg += v / static_cast<double>(hull->vertices.size());
        }
        double t = (Pu.topLeftCorner<3, 3>().trace() - mg * cg.squaredNorm()) / (3.0 * mg);
        if (!(t > 1e-6 * len * len) || !std::isfinite(t)) t = hull ? std::pow(0.25 * hull->size, 2) : len * len / 3.0;
        Eigen::Matrix4d P0 = Eigen::Matrix4d::Zero();
        P0.topLeftCorner<3, 3>() = mg * (cg * cg.transpose() + t * Eigen::Matrix3d::Identity());
        P0.topRightCorner<3, 1>() = mg * cg;
        P0.bottomLeftCorner<1, 3>() = mg * cg.transpose();
        P0(3, 3) = mg;
        const Eigen::Matrix4d G = (D.asDiagonal() * P0 * D.asDiagonal()).inverse();
        for (int k = 0; k < 10; ++k) model.q(k) = kPi[k] == kPj[k] ? G(kPi[k], kPi[k]) : 2.0 * G(kPi[k], kPj[k]);
        model.w = o.regularization;
        out.notes.push_back(absl::StrFormat(
            "weak entropic regularisation (weight %g) towards m %.4g, c (%.4g, %.4g, %.4g), isotropic second "
            "moment %.3g m^2 per axis",
            o.regularization, mg, cg.x(), cg.y(), cg.z(), t));
      }
      theta = ThetaFromP(Pt);
      for (int i = 0; i < 4; ++i) theta(i) = std::max(theta(i), kMinLogDiag);
      have_theta = true;
    }
    theta = Newton(model, theta, o.max_iterations, &out.iterations);
    // CoM-in-hull rows: SLSQP when the unconstrained optimum violates them.
    if (!model.rows.empty()) {
      const Eigen::Matrix4d U = UFromTheta(theta);
      const Vector10d p = PVec(U * U.transpose());
      double worst = -1;
      for (const auto& a : model.rows) worst = std::max(worst, a.dot(p) / p(pidx(3, 3)));
      if (worst > 1e-9) {
        SlsqpData data{&model};
        nlopt_opt opt = nlopt_create(NLOPT_LD_SLSQP, 10);
        nlopt_set_min_objective(opt, SlsqpObjective, &data);
        double lb[10];
        for (int i = 0; i < 10; ++i) lb[i] = i < 4 ? kMinLogDiag : -HUGE_VAL;
        nlopt_set_lower_bounds(opt, lb);
        std::vector<double> tol(model.rows.size(), 1e-12);
        nlopt_add_inequality_mconstraint(opt, static_cast<unsigned>(model.rows.size()), SlsqpConstraints, &data,
                                         tol.data());
        nlopt_set_ftol_rel(opt, 1e-15);
        nlopt_set_xtol_rel(opt, 1e-12);
        nlopt_set_maxeval(opt, 20 * o.max_iterations);
        double x[10], fmin = 0;
        for (int i = 0; i < 10; ++i) x[i] = theta(i);
        const nlopt_result res = nlopt_optimize(opt, x, &fmin);
        nlopt_destroy(opt);
        out.iterations += data.evals;
        Vector10d th2 = Eigen::Map<Vector10d>(x);
        if (res > 0 && th2.allFinite()) {
          theta = th2;
          if (round == o.reweighting_rounds - 1) out.notes.push_back("CoM-in-hull constraint active (SLSQP)");
        } else {
          out.notes.push_back(absl::StrCat("SLSQP for the hull rows failed (nlopt code ", static_cast<int>(res),
                                           "); CoM may lie outside the hull"));
        }
      }
    }
    const Eigen::Matrix4d U = UFromTheta(theta);
    pi = T * PVec(U * U.transpose());
    if (o.progress) o.progress(0.9 * (round + 1) / o.reweighting_rounds);
  }
  out.pi = pi;
  out.info = A;
  // Covariance of pi: (A)^+ (the unconstrained GLS information).
  out.cov = ScaledPseudoInverse(A, out.scale, 1e-14);
  out.samples_used = n;
  ResidualRms(kin, wrench, pi, &out.rms_force, &out.rms_torque);
  return out;
}

}  // namespace tactforce::inertia::internal
