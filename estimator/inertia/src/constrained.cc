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
#include "gls.h"
#include "internal.h"
#include "tactforce/inertia/pseudo_inertia.h"

namespace tactforce::inertia::internal {
namespace {

// theta: log-Cholesky coordinates of the scaled pseudo-inertia; p: its
// entries (pseudo_inertia.h), both indexed by kUr/kUc.
using LC = LogCholeskyParameters;
constexpr const int* kUr = LC::kRow;
constexpr const int* kUc = LC::kCol;

Eigen::Matrix4d UFromTheta(const Vector10d& th) { return LC{th}.U(); }

// Entries p of U U^T.
Vector10d EntriesOfFactor(const Eigen::Matrix4d& U) {
  return PseudoInertiaD::FromMatrix(Eigen::Matrix4d(U * U.transpose())).Entries();
}

// The quadratic model in scaled pseudo-inertia entries p:
//   f = 1/2 p^T A p - b^T p + w (q^T p - log det P)   (+ const)
struct Model {
  Matrix10d A;
  Vector10d b;
  double w = 0;  // prior weight
  Vector10d q = Vector10d::Zero();
  double scale = 1.0;           // objective divisor (conditioning)
  std::vector<Vector10d> rows;  // hull rows a^T p <= 0
  double row_length = 1.0;      // (a^T p / p_mass) * row_length = signed distance to the hull (m)
  double hull_size = 0.0;       // the hull's bounding-box diagonal (m)

  double F(const Vector10d& th) const {
    const Eigen::Matrix4d U = UFromTheta(th);
    const Vector10d p = EntriesOfFactor(U);
    double f = 0.5 * p.dot(A * p) - b.dot(p);
    if (w > 0) f += w * (q.dot(p) - 2.0 * th.head<4>().sum());
    return f / scale;
  }

  // Value, gradient and exact Hessian in theta.
  double Eval(const Vector10d& th, Vector10d* g, Matrix10d* H) const {
    const Eigen::Matrix4d U = UFromTheta(th);
    const Vector10d p = EntriesOfFactor(U);
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
        if (kUr[k] == kUc[k])
          Gm(kUr[k], kUr[k]) = gp(k);
        else
          Gm(kUr[k], kUc[k]) = Gm(kUc[k], kUr[k]) = 0.5 * gp(k);
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
      const int i = kUr[k], j = kUc[k];
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
  return LC::FromPseudoInertia(
             PseudoInertiaD::FromMatrix(Eigen::Matrix4d(0.5 * (P + P.transpose()))))
      .theta;
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

void SlsqpConstraints(unsigned m, double* result, unsigned n, const double* x, double* grad,
                      void* data) {
  auto* d = static_cast<SlsqpData*>(data);
  const Vector10d th = Eigen::Map<const Vector10d>(x);
  const Eigen::Matrix4d U = UFromTheta(th);
  const Vector10d p = EntriesOfFactor(U);
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

// Index of the scaled pseudo-inertia entry P(i, j) in p (i, j in 0..3).
constexpr int PIndex(int i, int j) { return LC::Index(i, j); }

// Minimum-norm solution of M x = r, M symmetric positive semi-definite:
// eigen-directions below 1e-14 of the largest eigenvalue are dropped.
template <typename Derived>
Vector10d MinimumNormSolve(const Eigen::MatrixBase<Derived>& M, const Vector10d& r) {
  Eigen::SelfAdjointEigenSolver<Matrix10d> es(M);
  Vector10d x = Vector10d::Zero();
  const double top = es.eigenvalues()(9);
  for (int i = 0; i < 10; ++i) {
    const double l = es.eigenvalues()(i);
    if (l > 1e-14 * top) x += es.eigenvectors().col(i) * (es.eigenvectors().col(i).dot(r) / l);
  }
  return x;
}

// The weights q of the log-det barrier term w (q^T p - log det P) whose
// minimum is at P0 (unscaled pseudo-inertia): q^T p = tr((D P0 D)^-1 P).
Vector10d BarrierWeights(const Eigen::Vector4d& D, const Eigen::Matrix4d& P0) {
  const Eigen::Matrix4d G = (D.asDiagonal() * P0 * D.asDiagonal()).inverse();
  Vector10d q;
  for (int k = 0; k < 10; ++k)
    q(k) = kUr[k] == kUc[k] ? G(kUr[k], kUr[k]) : 2.0 * G(kUr[k], kUc[k]);
  return q;
}

// Scales of the problem: the unweighted start pi (normal equations,
// minimum norm in scaled parameters), the mass m0 and length `len` that make
// the scaled pseudo-inertia O(1) (from the prior when one is given), and the
// parameter scale they imply.
struct Scales {
  Vector10d pi;
  double m0 = 1, len = 0.1;
  Vector10d parameter_scale;
};

Scales UnweightedStart(const GlsData& gls, const InertiaOptions& o, const ConvexHull* hull) {
  auto solve_scaled = [&](const Vector10d& scale) {
    const Matrix10d S = scale.asDiagonal();
    return Vector10d(S * MinimumNormSolve(S * gls.YtY * S, Vector10d(S * gls.Ytb)));
  };
  Scales sc;
  sc.pi = solve_scaled(Vector10d::Ones());
  RoughScale(sc.pi, hull, &sc.m0, &sc.len);
  if (o.prior) RoughScale(o.prior->params.ToStandard(), hull, &sc.m0, &sc.len);
  sc.parameter_scale = ParameterScale(sc.m0, sc.len);
  sc.pi = solve_scaled(sc.parameter_scale);
  // Second pass for the scale from a better estimate.
  double m1 = sc.m0, l1 = sc.len;
  RoughScale(sc.pi, hull, &m1, &l1);
  if (!o.prior) sc.m0 = m1, sc.len = l1;
  sc.parameter_scale = ParameterScale(sc.m0, sc.len);
  return sc;
}

// Scaled pseudo-inertia coordinates: p holds the entries of D P D with
// D = diag(1/(len sqrt(m0)) x3, 1/sqrt(m0)), and pi = T p.
struct ScaledCoordinates {
  Eigen::Vector4d D;
  Matrix10d T = Matrix10d::Zero();
};

ScaledCoordinates MakeScaledCoordinates(double m0, double len) {
  ScaledCoordinates c;
  const double dl = 1.0 / (len * std::sqrt(m0)), dm = 1.0 / std::sqrt(m0);
  c.D = Eigen::Vector4d(dl, dl, dl, dm);
  auto unscale = [&](int i, int j) { return 1.0 / (c.D(i) * c.D(j)); };
  Matrix10d& T = c.T;
  T(0, PIndex(3, 3)) = unscale(3, 3);
  for (int i = 0; i < 3; ++i) T(1 + i, PIndex(i, 3)) = unscale(i, 3);
  // I_o = tr(Sigma) I - Sigma
  T(4, PIndex(1, 1)) = unscale(1, 1), T(4, PIndex(2, 2)) = unscale(2, 2);
  T(5, PIndex(0, 0)) = unscale(0, 0), T(5, PIndex(2, 2)) = unscale(2, 2);
  T(6, PIndex(0, 0)) = unscale(0, 0), T(6, PIndex(1, 1)) = unscale(1, 1);
  T(7, PIndex(0, 1)) = -unscale(0, 1);
  T(8, PIndex(0, 2)) = -unscale(0, 2);
  T(9, PIndex(1, 2)) = -unscale(1, 2);
  return c;
}

// The parts of the model that do not change between rounds: the prior's
// barrier and the CoM-in-hull rows a^T p <= 0.
Model FixedModelTerms(const ScaledCoordinates& sc, double len, const InertiaOptions& o,
                      const ConvexHull* hull) {
  Model model;
  if (o.prior && o.prior->weight > 0) {
    model.q = BarrierWeights(sc.D, PseudoInertiaD::FromParameters(o.prior->params).Matrix());
    model.w = o.prior->weight;
  }
  if (hull) {
    model.row_length = len;
    model.hull_size = hull->size;
    for (size_t j = 0; j < hull->normals.size(); ++j) {
      Vector10d a = Vector10d::Zero();
      for (int i = 0; i < 3; ++i) a(PIndex(i, 3)) = hull->normals[j](i);
      a(PIndex(3, 3)) = -hull->offsets[j] / len;
      // a^T p = (n.h - d m) * dm^2 / len with h, m unscaled: <= 0 inside.
      model.rows.push_back(a);
    }
  }
  return model;
}

// Without a prior: a weak entropic regulariser towards an isotropic guess
// (scaled units) built from the projected GLS estimate Pt (scaled).
void AddEntropicRegulariser(const Eigen::Matrix4d& Pt, const ScaledCoordinates& sc,
                            const Scales& scales, const InertiaOptions& o, const ConvexHull* hull,
                            Model* model, std::vector<std::string>* notes) {
  const double len = scales.len;
  const Eigen::Matrix4d Pu = sc.D.asDiagonal().inverse() * Pt * sc.D.asDiagonal().inverse();
  double mg = Pu(3, 3) > 0 && std::isfinite(Pu(3, 3)) ? Pu(3, 3) : scales.m0;
  Vec3 cg = Pu.topRightCorner<3, 1>() / mg;
  if (!cg.allFinite()) cg.setZero();
  if (hull && !hull->Contains(cg, 1e-9)) {
    cg.setZero();
    for (const Vec3& v : hull->vertices) cg += v / static_cast<double>(hull->vertices.size());
  }
  double t = (Pu.topLeftCorner<3, 3>().trace() - mg * cg.squaredNorm()) / (3.0 * mg);
  if (!(t > 1e-6 * len * len) || !std::isfinite(t))
    t = hull ? std::pow(0.25 * hull->size, 2) : len * len / 3.0;
  PseudoInertiaD guess;
  guess.mass = mg;
  guess.h = mg * cg;
  guess.sigma = mg * (cg * cg.transpose() + t * Eigen::Matrix3d::Identity());
  model->q = BarrierWeights(sc.D, guess.Matrix());
  model->w = o.constrained.regularization;
  notes->push_back(
      absl::StrFormat("weak entropic regularisation (weight %g) towards m %.4g, c (%.4g, %.4g, "
                      "%.4g), isotropic second "
                      "moment %.3g m^2 per axis",
                      o.constrained.regularization, mg, cg.x(), cg.y(), cg.z(), t));
}

// The start of the first Newton solve: the unconstrained GLS estimate of
// the model, averaged with the prior when given, projected into the
// positive definite cone. Adds the regulariser to the model when asked.
Vector10d InitialTheta(const ScaledCoordinates& sc, const Scales& scales, const InertiaOptions& o,
                       const ConvexHull* hull, Model* model, std::vector<std::string>* notes) {
  const Vector10d p = MinimumNormSolve(model->A, model->b);
  Eigen::Matrix4d Pt = PseudoInertiaD::FromEntries(p).Matrix();
  if (o.prior) {
    const Eigen::Matrix4d prior = PseudoInertiaD::FromParameters(o.prior->params).Matrix();
    Pt = 0.5 * Pt + 0.5 * sc.D.asDiagonal() * prior * sc.D.asDiagonal();
  }
  if (!o.prior && o.constrained.regularization > 0)
    AddEntropicRegulariser(Pt, sc, scales, o, hull, model, notes);
  Vector10d theta = ThetaFromP(Pt);
  for (int i = 0; i < 4; ++i) theta(i) = std::max(theta(i), kMinLogDiag);
  return theta;
}

// A CoM the data place outside the hull by more than this fraction of the
// hull's size gets a warning note.
constexpr double kHullContradiction = 0.02;

// The CoM-in-hull rows by SLSQP (NLopt) from `theta`, when the
// unconstrained optimum violates them. Returns the constrained optimum, or
// `theta` (noted) when SLSQP fails.
Vector10d EnforceHullRows(const Model& model, const Vector10d& theta, const InertiaOptions& o,
                          bool last_round, MethodOutput* out) {
  const Eigen::Matrix4d U = UFromTheta(theta);
  const Vector10d p = EntriesOfFactor(U);
  double worst = -1;
  for (const auto& a : model.rows) worst = std::max(worst, a.dot(p) / p(PIndex(3, 3)));
  if (!(worst > 1e-9)) return theta;
  // The data put the CoM this far outside: more than a sliver means the hull
  // probably does not contain the object's CoM, and the fit held on its
  // boundary has biased mass and inertia.
  const double outside = worst * model.row_length;
  if (last_round && outside > kHullContradiction * model.hull_size) {
    out->notes.push_back(absl::StrFormat(
        "warning: the data put the CoM %.1f mm outside the given hull (%.0f%% of its size); the "
        "fit is held on "
        "the hull's boundary, so mass, CoM and inertia are biased if the hull is wrong: check it",
        1e3 * outside, 100 * outside / model.hull_size));
  }
  SlsqpData data{&model};
  nlopt_opt opt = nlopt_create(NLOPT_LD_SLSQP, 10);
  nlopt_set_min_objective(opt, SlsqpObjective, &data);
  double lb[10];
  for (int i = 0; i < 10; ++i) lb[i] = i < 4 ? kMinLogDiag : -HUGE_VAL;
  nlopt_set_lower_bounds(opt, lb);
  std::vector<double> tol(model.rows.size(), 1e-12);
  nlopt_add_inequality_mconstraint(opt, static_cast<unsigned>(model.rows.size()), SlsqpConstraints,
                                   &data, tol.data());
  nlopt_set_ftol_rel(opt, 1e-15);
  nlopt_set_xtol_rel(opt, 1e-12);
  nlopt_set_maxeval(opt, 20 * o.max_iterations);
  double x[10], fmin = 0;
  for (int i = 0; i < 10; ++i) x[i] = theta(i);
  const nlopt_result res = nlopt_optimize(opt, x, &fmin);
  nlopt_destroy(opt);
  out->iterations += data.evals;
  const Vector10d th2 = Eigen::Map<Vector10d>(x);
  if (res > 0 && th2.allFinite()) {
    if (last_round) out->notes.push_back("CoM-in-hull constraint active (SLSQP)");
    return th2;
  }
  out->notes.push_back(absl::StrCat("SLSQP for the hull rows failed (nlopt code ",
                                    static_cast<int>(res), "); CoM may lie outside the hull"));
  return theta;
}

// One GLS round's data term of the model at the current estimate pi
// (weights and errors-in-variables bias from pi). Returns the uncorrected
// information matrix A.
Matrix10d UpdateDataTerm(const GlsData& gls, const Vector10d& pi, const ScaledCoordinates& sc,
                         const Vector10d& parameter_scale, bool last_round, Model* model,
                         std::vector<std::string>* notes, InterruptPoll* poll) {
  GlsSums sums;
  AccumulateGls(gls, pi, poll, &sums);
  // Subtract the bias when the corrected matrix stays well positive definite.
  bool corrected = false;
  const Matrix10d Ause = BiasCorrected(sums, parameter_scale, &corrected);
  if (corrected && last_round) notes->push_back("errors-in-variables bias correction applied");
  model->A = sc.T.transpose() * Ause * sc.T;
  model->b = sc.T.transpose() * sums.b;
  model->scale = std::max(model->A.diagonal().cwiseAbs().maxCoeff(), 1e-300);
  return sums.A;
}

}  // namespace

absl::StatusOr<MethodOutput> FitConstrained(const InertiaSamples& s, const InertiaOptions& o,
                                            const ConvexHull* hull) {
  InterruptPoll poll(o.interrupt);
  MethodOutput out;
  const GlsData gls = PrepareGls(s, o, &out.notes, &poll);
  if (poll.stopped()) return Interrupted();
  const Scales scales = UnweightedStart(gls, o, hull);
  out.scale = scales.parameter_scale;
  const ScaledCoordinates sc = MakeScaledCoordinates(scales.m0, scales.len);
  Model model = FixedModelTerms(sc, scales.len, o, hull);

  Vector10d pi = scales.pi;
  Vector10d theta;
  Matrix10d A = Matrix10d::Zero();
  for (int round = 0; round < o.reweighting_rounds; ++round) {
    if (poll.Check()) return Interrupted();
    const bool last_round = round == o.reweighting_rounds - 1;
    A = UpdateDataTerm(gls, pi, sc, out.scale, last_round, &model, &out.notes, &poll);
    if (poll.stopped()) return Interrupted();
    if (round == 0) theta = InitialTheta(sc, scales, o, hull, &model, &out.notes);
    theta = Newton(model, theta, o.max_iterations, &out.iterations);
    if (!model.rows.empty()) theta = EnforceHullRows(model, theta, o, last_round, &out);
    const Eigen::Matrix4d U = UFromTheta(theta);
    pi = sc.T * EntriesOfFactor(U);
    if (o.progress) o.progress(0.9 * (round + 1) / o.reweighting_rounds);
  }
  out.pi = pi;
  out.info = A;
  // Covariance of pi: (A)^+ (the unconstrained GLS information).
  out.cov = ScaledPseudoInverse(A, out.scale, 1e-14);
  out.samples_used = static_cast<int>(gls.kin.size());
  ResidualRms(gls.kin, gls.wrench, pi, &poll, &out.rms_force, &out.rms_torque);
  if (poll.stopped()) return Interrupted();
  return out;
}

}  // namespace tactforce::inertia::internal
