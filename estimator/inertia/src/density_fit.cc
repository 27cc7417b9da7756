// DENSITY: non-negative, piecewise-constant density over the regions of a
// closed mesh. The standard parameters are linear in the K densities,
// pi = Phi rho, so the GLS data term of CONSTRAINED becomes a quadratic in
// rho; with a smoothness penalty between neighbouring regions the fit is a
// non-negative quadratic programme in K unknowns (the planner's dense QP). The
// penalty's strength is chosen by held-out contiguous time blocks.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "gls.h"
#include "internal.h"
#include "tactforce/inertia/pseudo_inertia.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/planner/dense_qp.h"

namespace tactforce::inertia::internal {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// min 1/2 u^T Q u - g^T u  s.t. u >= 0, Q symmetric positive definite, on
// the planner's dense QP (rows -u_i <= 0). The bounds active at the answer
// are exactly 0 (the covariance's free set is u > 0). Counts 1 + the QP's
// steps into `iterations`; polls once per solve (~1 unit per microsecond).
// Counts of the non-negative solves of one fit.
struct QpCounts {
  int iterations = 0;  // 1 per solve plus the QP's active-set steps
  int failures = 0;    // solves that did not end optimal (their answer is zero)
};

VectorXd NonNegativeQp(const MatrixXd& Q, const VectorXd& g, QpCounts* counts,
                       InterruptPoll* poll) {
  const int K = static_cast<int>(g.size());
  const int64_t k3 = static_cast<int64_t>(K) * K * K;
  if (poll->Tick(1 + k3 / 100)) return VectorXd::Zero(K);
  planner::DenseQp qp;
  qp.hessian = Q;
  qp.gradient = -g;
  qp.in_matrix = -MatrixXd::Identity(K, K);
  qp.in_rhs = VectorXd::Zero(K);
  const planner::DenseQpResult r = planner::SolveDenseQp(qp);
  counts->iterations += 1 + r.iterations;
  if (r.status != planner::DenseQpStatus::kOptimal || !r.x.allFinite()) {
    ++counts->failures;
    return VectorXd::Zero(K);
  }
  VectorXd u = r.x.cwiseMax(0.0);
  for (int i : r.active_set) u(i) = 0.0;
  return u;
}

// The quadratic data term in u = rho / rho_ref: 1/2 u^T H u - g^T u + c/2.
struct Quadratic {
  MatrixXd H;
  VectorXd g;
  double c = 0;
  double Value(const VectorXd& u) const { return u.dot(H * u) - 2 * g.dot(u) + c; }  // = chi^2
};

Quadratic Project(const Matrix10d& A, const Vector10d& b, double c, const MatrixXd& Phi) {
  Quadratic q;
  q.H = Phi.transpose() * A * Phi;
  q.g = Phi.transpose() * b;
  q.c = c;
  return q;
}

// Free 10-parameter GLS solution of A pi = b (scaled pseudo-inverse).
Vector10d FreeGls(const Matrix10d& A, const Vector10d& b, const Vector10d& scale) {
  return ScaledPseudoInverse(A, scale, 1e-12) * b;
}

// The CoM the data imply (free GLS fit) must lie in the mesh's bounding box,
// up to 1 % of its diagonal plus 5 standard errors of that CoM.
absl::Status CheckComInBoundingBox(const GlsSums& sums, const Vector10d& scale,
                                   const InertiaOptions& o) {
  if (!o.mesh) return absl::OkStatus();
  Eigen::AlignedBox3d box;
  for (const Vec3& v : o.mesh->vertices) box.extend(v);
  const Matrix10d cov = ScaledPseudoInverse(sums.A, scale, 1e-12);
  const Vector10d free = cov * sums.b;
  const double m = free(0);
  if (!(m > 0) || box.isEmpty()) return absl::OkStatus();
  const Vec3 com = free.segment<3>(1) / m;
  double se = 0;  // largest standard error of a CoM component (first order)
  for (int i = 0; i < 3; ++i) {
    const double var =
        (cov(1 + i, 1 + i) - 2 * com(i) * cov(1 + i, 0) + com(i) * com(i) * cov(0, 0)) / (m * m);
    se = std::max(se, std::sqrt(std::max(var, 0.0)));
  }
  const double outside = box.exteriorDistance(com);
  if (outside > 0.01 * box.diagonal().norm() + 5 * se) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: the CoM of the data (%.4g, %.4g, %.4g) m is outside the mesh's "
                        "bounding box by %.3g m (standard error "
                        "%.2g m): check the mesh's scale and object_in_mesh",
                        o.mesh_name, com.x(), com.y(), com.z(), outside, se));
  }
  return absl::OkStatus();
}

// The unknowns u = rho / rho_ref of the fit: pi = Phi_u u, with rho_ref the
// uniform density that fits the unweighted equations best; the smoothness
// penalty u^T L u between neighbouring regions; the parameter scale.
struct DensityBasis {
  int K = 0;
  double rho_ref = 0;
  MatrixXd Phi_u;        // 10 x K
  Vector10d pi_uniform;  // the uniform solid at rho_ref
  MatrixXd L;            // K x K
  double l_scale = 1;    // mean diagonal of L (1 without neighbours)
  Vector10d parameter_scale;
  const std::vector<Vec3>* mesh_vertices = nullptr;  // for the object's size
};

absl::StatusOr<DensityBasis> MakeDensityBasis(const GlsData& gls, const RegionModel& regions,
                                              const InertiaOptions& o) {
  DensityBasis b;
  b.K = static_cast<int>(regions.regions.size());
  const int K = b.K;
  const double volume = regions.total.volume;
  // Columns: standard parameters of each region at 1 kg/m^3.
  MatrixXd Phi(10, K);
  for (int r = 0; r < K; ++r) Phi.col(r) = regions.regions[r].moments.Standard(1.0);
  const Vector10d phi_total = regions.total.Standard(1.0);
  // Reference density: the uniform solid fitted to the unweighted equations.
  b.rho_ref = phi_total.dot(gls.Ytb) / std::max(phi_total.dot(gls.YtY * phi_total), 1e-300);
  if (!(b.rho_ref > 0) || !std::isfinite(b.rho_ref)) {
    return absl::InvalidArgumentError(absl::StrCat(
        o.mesh_name, ": the data give a non-positive mass for the mesh (", b.rho_ref * volume,
        " kg): check the force signs, gravity and the mesh's scale"));
  }
  const double length = std::sqrt(std::max(regions.total.second.trace() / volume, 1e-12));
  b.parameter_scale = ParameterScale(b.rho_ref * volume, length);
  // Smoothness penalty sum_ij w_ij (u_i - u_j)^2 = u^T L u.
  b.L = MatrixXd::Zero(K, K);
  for (size_t e = 0; e < regions.neighbours.size(); ++e) {
    const int i = regions.neighbours[e][0], j = regions.neighbours[e][1];
    const double w = regions.neighbour_weights[e];
    b.L(i, i) += w, b.L(j, j) += w, b.L(i, j) -= w, b.L(j, i) -= w;
  }
  b.l_scale = b.L.trace() > 0 ? b.L.trace() / K : 1.0;
  b.Phi_u = Phi * b.rho_ref;
  b.pi_uniform = phi_total * b.rho_ref;
  if (o.mesh) b.mesh_vertices = &o.mesh->vertices;
  return b;
}

// The fit's state across re-weighting rounds; after the last round, that
// round's sums and quadratics (for the covariance and the contradiction test).
struct DensityState {
  Vector10d pi;
  VectorXd u;
  double lambda_rel = 0;  // smoothness strength relative to the data's curvature
  QpCounts qp;
  GlsSums total;
  std::vector<GlsSums> blocks;      // per held-out time block
  std::vector<Matrix6d> whiteners;  // per sample (last round)
  Quadratic full;
  std::vector<Quadratic> train, held;  // per fold: the other blocks, the block
  MatrixXd Hreg;                       // full.H + penalty + ridge
};

// Per fold: the data term of the other blocks (bias-corrected) and of the
// held-out block.
void FoldQuadratics(const DensityBasis& b, int folds, DensityState* st) {
  st->train.assign(folds, Quadratic());
  st->held.assign(folds, Quadratic());
  for (int f = 0; f < folds; ++f) {
    const GlsSums& blk = st->blocks[f];
    GlsSums rest = st->total;
    rest.A -= blk.A, rest.b -= blk.b, rest.c -= blk.c, rest.bias -= blk.bias;
    bool fold_corrected = false;
    st->train[f] =
        Project(BiasCorrected(rest, b.parameter_scale, &fold_corrected), rest.b, rest.c, b.Phi_u);
    st->held[f] = Project(blk.A, blk.b, blk.c, b.Phi_u);
  }
}

// Held-out weighted residual over a log grid of strengths (relative to the
// data's mean curvature per region); the smallest wins, ties go to the
// smoother fit.
double ChooseStrength(const DensityBasis& b, const MatrixXd& ridge, DensityState* st,
                      InterruptPoll* poll) {
  const int K = b.K, folds = static_cast<int>(st->train.size());
  double best = std::numeric_limits<double>::infinity();
  double chosen = st->lambda_rel;
  for (int e = 12; e >= -7; --e) {
    const double rel = e == -7 ? 0.0 : std::pow(10.0, e);
    double cv = 0;
    for (int f = 0; f < folds; ++f) {
      const double tr_scale = std::max(st->train[f].H.trace() / K, 1e-300);
      const VectorXd uf = NonNegativeQp(st->train[f].H + rel * tr_scale / b.l_scale * b.L + ridge,
                                        st->train[f].g, &st->qp, poll);
      if (poll->stopped()) return chosen;
      cv += st->held[f].Value(uf);
    }
    if (cv < best * (1 - 1e-9)) best = cv, chosen = rel;
  }
  return chosen;
}

// One re-weighting round: GLS sums at the current pi, the data term, the
// strength (when chosen), and the non-negative solve.
absl::Status DensityRound(const GlsData& gls, const DensityBasis& b, const RegionModel& regions,
                          const InertiaOptions& o, int round, int folds, bool choose,
                          DensityState* st, MethodOutput* out, InterruptPoll* poll) {
  const int K = b.K;
  const bool last = round == o.reweighting_rounds - 1;
  AccumulateGls(gls, st->pi, poll, &st->total, folds, &st->blocks, last ? &st->whiteners : nullptr);
  if (poll->stopped()) return Interrupted();
  if (round == 0) {
    TF_RETURN_IF_ERROR(CheckComInBoundingBox(st->total, b.parameter_scale, o));
  }
  bool corrected = false;
  const Matrix10d A = BiasCorrected(st->total, b.parameter_scale, &corrected);
  if (corrected && last) out->notes.push_back("errors-in-variables bias correction applied");
  st->full = Project(A, st->total.b, st->total.c, b.Phi_u);
  out->info = st->total.A;
  // A small ridge keeps the QP strictly convex when K exceeds what the
  // data determine and no smoothing is used.
  const double h_scale = std::max(st->full.H.trace() / K, 1e-300);
  const MatrixXd ridge = 1e-10 * h_scale * MatrixXd::Identity(K, K);
  FoldQuadratics(b, folds, st);
  if (choose && K > 1 && !regions.neighbours.empty())
    st->lambda_rel = ChooseStrength(b, ridge, st, poll);
  st->Hreg = st->full.H + st->lambda_rel * h_scale / b.l_scale * b.L + ridge;
  const int failures_before = st->qp.failures;
  st->u = NonNegativeQp(st->Hreg, st->full.g, &st->qp, poll);
  st->pi = b.Phi_u * st->u;
  if (poll->stopped()) return Interrupted();
  if (st->qp.failures > failures_before)
    return absl::InternalError(absl::StrCat("DENSITY round ", round + 1,
                                            ": the non-negative density solve did not converge"));
  return absl::OkStatus();
}

// Standard errors of the densities and the covariance of pi on the free set
// (u > 0): Q^-1 H Q^-1 with Q = H + lambda L.
void DensityCovariance(const DensityBasis& b, const DensityState& st, MethodOutput* out) {
  std::vector<int> idx;
  for (int r = 0; r < b.K; ++r)
    if (st.u(r) > 0) idx.push_back(r);
  const int m = static_cast<int>(idx.size());
  MatrixXd Qf(m, m), Hf(m, m);
  for (int a = 0; a < m; ++a)
    for (int c = 0; c < m; ++c)
      Qf(a, c) = st.Hreg(idx[a], idx[c]), Hf(a, c) = st.full.H(idx[a], idx[c]);
  out->density_se.assign(b.K, 0.0);
  if (m == 0) return;
  const MatrixXd Qi = Qf.ldlt().solve(MatrixXd::Identity(m, m));
  const MatrixXd cov_u = Qi * Hf * Qi;
  MatrixXd Pf(10, m);
  for (int a = 0; a < m; ++a) {
    out->density_se[idx[a]] = b.rho_ref * std::sqrt(std::max(cov_u(a, a), 0.0));
    Pf.col(a) = b.Phi_u.col(idx[a]);
  }
  out->cov = Pf * cov_u * Pf.transpose();
}

// Contradiction statistic: held-out residual per sample of DENSITY against
// the free 10-parameter GLS fit (the model CONSTRAINED regularises), each
// fitted on the other blocks with the last round's weights.
void HeldOutContradiction(const GlsData& gls, const DensityBasis& b, int folds, DensityState* st,
                          MethodOutput* out, InterruptPoll* poll) {
  const int n = static_cast<int>(gls.kin.size()), K = b.K;
  std::vector<Vector10d> pi_density(folds), pi_free(folds);
  for (int f = 0; f < folds; ++f) {
    const double tr_scale = std::max(st->train[f].H.trace() / K, 1e-300);
    const double h_scale = std::max(st->full.H.trace() / K, 1e-300);
    const VectorXd uf = NonNegativeQp(st->train[f].H + st->lambda_rel * tr_scale / b.l_scale * b.L +
                                          1e-10 * h_scale * MatrixXd::Identity(K, K),
                                      st->train[f].g, &st->qp, poll);
    pi_density[f] = b.Phi_u * uf;
    pi_free[f] =
        FreeGls(st->total.A - st->blocks[f].A, st->total.b - st->blocks[f].b, b.parameter_scale);
  }
  double sum_d = 0, sum_d2 = 0, res_density = 0, res_free = 0;
  double diff_f = 0, diff_t = 0;  // prediction differences, per kind
  double accel2 = 0;              // |a - g|^2 in the object frame
  for (int k = 0; k < n; ++k) {
    if (poll->Tick()) return;
    const int f = BlockOf(k, n, folds);
    const Vector6d ed = gls.Y[k] * pi_density[f] - gls.wrench[k];
    const Vector6d ef = gls.Y[k] * pi_free[f] - gls.wrench[k];
    const double rd = (st->whiteners[k] * ed).squaredNorm();
    const double rf = (st->whiteners[k] * ef).squaredNorm();
    res_density += rd, res_free += rf;
    sum_d += rd - rf, sum_d2 += (rd - rf) * (rd - rf);
    const Vector6d dp = ed - ef;
    diff_f += dp.head<3>().squaredNorm(), diff_t += dp.tail<3>().squaredNorm();
    accel2 += gls.kin[k].a_minus_g.squaredNorm();
  }
  const double mg = std::abs(st->pi(0)) * std::sqrt(accel2 / n);
  out->heldout_mass_equivalent = mg > 0 ? std::sqrt(diff_f / n) / mg : 0;
  out->heldout_com_equivalent = mg > 0 ? std::sqrt(diff_t / n) / mg : 0;
  Eigen::AlignedBox3d box;
  for (const Vec3& v : b.mesh_vertices ? *b.mesh_vertices : std::vector<Vec3>()) box.extend(v);
  out->mesh_size = box.isEmpty() ? 0 : box.diagonal().norm();

  const double mean = sum_d / n;
  const double var = std::max(sum_d2 / n - mean * mean, 0.0);
  out->heldout_ratio = res_free > 0 ? res_density / res_free : (res_density > 0 ? HUGE_VAL : 1.0);
  out->heldout_z = var > 0 ? mean / std::sqrt(var / n) : (mean > 0 ? HUGE_VAL : 0.0);
}

// Columns: the standard parameters of dP = S Z S for the 10 unit symmetric
// Z (off-diagonal pairs 1/sqrt(2) each), S = P_ref^(1/2). Then |z| = |S^-1
// dP S^-1|_F, the first-order affine-invariant (Riemannian) distance from
// P_ref: a relative mass error dm/m, a CoM move dc_i/(sqrt(2) s_i) with s_i
// the radius of gyration along axis i, relative second moments.
Matrix10d WhitenedBasis(const Eigen::Matrix4d& p_ref) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> es(p_ref);
  const double top = std::max(es.eigenvalues()(3), 1e-300);
  const Eigen::Vector4d root = es.eigenvalues().cwiseMax(1e-12 * top).cwiseSqrt();
  const Eigen::Matrix4d S = es.eigenvectors() * root.asDiagonal() * es.eigenvectors().transpose();
  Matrix10d G;
  int col = 0;
  for (int i = 0; i < 4; ++i) {
    for (int j = i; j < 4; ++j) {
      Eigen::Matrix4d Z = Eigen::Matrix4d::Zero();
      const double v = i == j ? 1.0 : std::sqrt(0.5);
      Z(i, j) = v, Z(j, i) = v;
      G.col(col++) = PseudoInertiaD::FromMatrix(Eigen::Matrix4d(S * Z * S)).Standard();
    }
  }
  return G;
}

// Pseudo-inverse of a symmetric positive semi-definite matrix (eigenvalues
// below 1e-14 of the largest dropped: round-off, not weak excitation).
Matrix10d SymmetricPseudoInverse(const Matrix10d& M) {
  Eigen::SelfAdjointEigenSolver<Matrix10d> es(0.5 * (M + M.transpose()));
  const double top = std::max(es.eigenvalues()(9), 1e-300);
  Vector10d inv;
  for (int i = 0; i < 10; ++i)
    inv(i) = es.eigenvalues()(i) > 1e-14 * top ? 1 / es.eigenvalues()(i) : 0.0;
  return es.eigenvectors() * inv.asDiagonal() * es.eigenvectors().transpose();
}

// The free GLS fit in the whitened coordinates z (pi = G z), re-weighted at
// its own estimate (when the wrench noise is estimated from residuals, the
// unrestricted model's residuals: right under both hypotheses, and a wrong
// density cannot whiten away its own misfit): x_f and its information as a
// sandwich A_z B_z^-1 A_z, B_z the spread of the scores of ~25-sample time
// blocks, so that correlated (smoothed) rows, misjudged noise and the
// errors-in-variables approximation do not make the ellipsoid too small
// (with A_z alone the right mesh of a simulated box at 'high' noise was
// 0.12 away).
struct FreeFit {
  Vector10d x;
  Matrix10d A;
};
FreeFit FreeFitOwnWeights(const GlsData& gls, const DensityBasis& b, const Matrix10d& G,
                          const Vector10d& pi0, InterruptPoll* poll) {
  FreeFit f;
  Vector10d pi = pi0;
  const int n = static_cast<int>(gls.kin.size());
  const int nblocks = std::max(10, n / 25);
  for (int round = 0; round < 2; ++round) {
    GlsSums sums;
    std::vector<GlsSums> blocks;
    AccumulateGls(gls, pi, poll, &sums, nblocks, &blocks);
    if (poll->stopped()) return f;
    bool corrected = false;
    f.A = G.transpose() * BiasCorrected(sums, b.parameter_scale, &corrected) * G;
    f.x = SymmetricPseudoInverse(f.A) * (G.transpose() * sums.b);
    pi = G * f.x;
    {  // sandwich: A B^-1 A with B the covariance of the block scores
      Matrix10d B = Matrix10d::Zero();
      for (const GlsSums& blk : blocks) {
        const Matrix10d Ab = G.transpose() * (corrected ? Matrix10d(blk.A - blk.bias) : blk.A) * G;
        const Vector10d sc = G.transpose() * blk.b - Ab * f.x;
        B += sc * sc.transpose();
      }
      const Matrix10d Ai = SymmetricPseudoInverse(f.A);
      f.A = SymmetricPseudoInverse(Ai * B * Ai);
    }
  }
  return f;
}

// The distance, in first-order Riemannian units at the density answer,
// between the densities the mesh's regions can carry (C u, u >= 0) and the
// parameters the data allow (x with (x - x_f)^T A_z (x - x_f) <= threshold):
// d^2 = max over nu >= 0 of min_u (C u - x_f)^T M_nu (C u - x_f) - nu
// threshold, M_nu = A_z (A_z + I / nu)^-1 (Lagrangian dual of the ellipsoid
// constraint; the inner minimum is a non-negative QP). Also T0, the least
// chi^2 excess of a realizable density (likelihood ratio).
struct MeshDistance {
  double distance = 0, t0 = 0;
};
MeshDistance DistanceToRealizable(const MatrixXd& C, const Vector10d& xf, const Matrix10d& Az,
                                  double threshold, DensityState* st, InterruptPoll* poll) {
  const int K = static_cast<int>(C.cols());
  Eigen::SelfAdjointEigenSolver<Matrix10d> es(0.5 * (Az + Az.transpose()));
  const Vector10d a = es.eigenvalues().cwiseMax(0.0);
  const Matrix10d V = es.eigenvectors();
  const MatrixXd Cv = V.transpose() * C;
  const Vector10d xv = V.transpose() * xf;
  // weight(i) of the metric for nu (nu = inf: the T0 metric a itself).
  auto solve = [&](const Vector10d& weight, VectorXd* u) {
    const MatrixXd H = Cv.transpose() * weight.asDiagonal() * Cv;
    const double scale = std::max(H.trace() / K, 1e-300);
    *u = NonNegativeQp(H + 1e-12 * scale * MatrixXd::Identity(K, K),
                       Cv.transpose() * weight.asDiagonal() * xv, &st->qp, poll);
    return Vector10d(Cv * *u - xv);
  };
  MeshDistance out;
  VectorXd u;
  const Vector10d r0 = solve(a, &u);
  out.t0 = r0.dot(a.asDiagonal() * r0);
  if (out.t0 <= threshold) return out;
  // Derivative of the dual in nu: sum a_i r_i^2 / (1 + nu a_i)^2 - threshold (decreasing).
  auto slope = [&](double nu, double* value) {
    Vector10d w;
    for (int i = 0; i < 10; ++i) w(i) = nu * a(i) / (1 + nu * a(i));
    const Vector10d r = solve(w, &u);
    double s = -threshold;
    for (int i = 0; i < 10; ++i) s += a(i) * r(i) * r(i) / ((1 + nu * a(i)) * (1 + nu * a(i)));
    *value = r.dot(w.asDiagonal() * r) - nu * threshold;
    return s;
  };
  // Bracket the root of the slope around 1 / (largest eigenvalue), then bisect in log nu.
  const double amax = std::max(a.maxCoeff(), 1e-300);
  double lo = 1e-6 / amax, hi = 1e6 / amax, value = 0;
  while (slope(hi, &value) > 0 && hi < 1e300 && !poll->stopped()) lo = hi, hi *= 1e6;
  while (slope(lo, &value) < 0 && lo > 1e-300 && !poll->stopped()) hi = lo, lo *= 1e-6;
  for (int it = 0; it < 60 && !poll->stopped(); ++it) {
    const double mid = std::sqrt(lo * hi);
    (slope(mid, &value) > 0 ? lo : hi) = mid;
  }
  slope(std::sqrt(lo * hi), &value);
  out.distance = std::sqrt(std::max(value, 0.0));
  return out;
}

// The chi^2 quantile (Wilson-Hilferty) for `dof` degrees of freedom at the
// standard-normal quantile z.
double ChiSquareQuantile(int dof, double z) {
  const double k = std::max(dof, 1);
  const double c = 1 - 2 / (9 * k) + z * std::sqrt(2 / (9 * k));
  return k * c * c * c;
}

// The mesh test (ReportDensity decides): how far, in first-order Riemannian units
// at the density answer, the densities the regions can carry are from the
// parameters the data allow at the 99.9 % chi^2 bound (10 degrees of
// freedom) of the free fit.
void MeshConsistency(const GlsData& gls, const DensityBasis& b, DensityState* st, MethodOutput* out,
                     InterruptPoll* poll) {
  const Matrix10d G = WhitenedBasis(PseudoInertiaD::FromStandard(st->pi).Matrix());
  const Eigen::FullPivLU<Matrix10d> lu(G);
  const FreeFit f = FreeFitOwnWeights(gls, b, G, st->pi, poll);
  if (poll->stopped()) return;
  const MatrixXd C = lu.solve(b.Phi_u);
  out->mesh_chi2_bound = ChiSquareQuantile(10, 3.0902);  // upper 0.1 %
  const MeshDistance m = DistanceToRealizable(C, f.x, f.A, out->mesh_chi2_bound, st, poll);
  out->mesh_distance = m.distance;
  out->mesh_chi2_excess = m.t0;
  const InertialParameters p = InertialParameters::FromStandard(st->pi);
  if (p.mass > 0) {
    const Eigen::Matrix3d ic = p.inertia_com.Matrix();
    const Eigen::Matrix3d sigma = 0.5 * ic.trace() * Eigen::Matrix3d::Identity() - ic;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sigma, Eigen::EigenvaluesOnly);
    out->gyration_radii = (es.eigenvalues().cwiseMax(0.0) / p.mass).cwiseSqrt();
  }
}

// DENSITY's answer in `fit` (region model, densities, strength, the
// held-out and mesh-test notes) and the mesh test's verdict: the data
// contradict the mesh when every density its regions can carry lies farther
// than o.density.mesh_tolerance, in first-order Riemannian units (the
// affine-invariant distance between pseudo-inertias, metrics.h), from every
// parameter vector the data allow (the free fit's 99.9 % chi^2 ellipsoid):
// significant AND physically large (kDefaultMeshTolerance says why 0.03).
void ReportDensity(std::shared_ptr<const RegionModel> model, const InertiaOptions& o,
                   MethodOutput* r, InertiaFit* fit) {
  for (size_t i = 0; i < model->regions.size(); ++i) {
    fit->densities.push_back({model->regions[i].label, r->densities[i],
                              model->regions[i].moments.volume, r->density_se[i]});
  }
  fit->region_model = std::move(model);
  fit->density_regularization = r->regularization;
  fit->density_regularization_rule = r->regularization_rule;
  fit->heldout_residual_ratio = r->heldout_ratio;
  r->notes.push_back(absl::StrFormat(
      "held-out weighted residual %.3gx the free 10-parameter fit's (z = %.3g over the held-out "
      "samples); the "
      "predicted wrenches differ like a mass error of %.2g %% and a CoM displacement of %.3g mm",
      r->heldout_ratio, r->heldout_z, 100 * r->heldout_mass_equivalent,
      1000 * r->heldout_com_equivalent));
  const Vec3& s = r->gyration_radii;
  const double tolerance = o.density.mesh_tolerance;
  r->notes.push_back(absl::StrFormat(
      "mesh test: the densities this mesh can carry are %.3g (first-order Riemannian) from the "
      "parameters the "
      "data allow (least chi^2 excess %.3g, bound %.3g at 99.9 %%); tolerance %g: a %g %% error of "
      "the mass or a "
      "principal second moment, or a CoM move of %.3g / %.3g / %.3g mm along the principal axes",
      r->mesh_distance, r->mesh_chi2_excess, r->mesh_chi2_bound, tolerance, 100 * tolerance,
      1000 * tolerance * s(0) / std::sqrt(2.0), 1000 * tolerance * s(1) / std::sqrt(2.0),
      1000 * tolerance * s(2) / std::sqrt(2.0)));
  if (!(tolerance > 0 && r->mesh_distance > tolerance)) {
    fit->density_realizable = true;
    return;
  }
  fit->mesh_contradicted = true;
  fit->mesh_contradiction = absl::StrFormat(
      "the data contradict the mesh: every density it can carry is %.3g (Riemannian, tolerance %g) "
      "from what the "
      "data allow; check scale and object_in_mesh (the answer is CONSTRAINED's; the densities are "
      "those of the "
      "rejected mesh fit)",
      r->mesh_distance, tolerance);
}

}  // namespace

absl::StatusOr<MethodOutput> FitDensity(const InertiaSamples& s, const InertiaOptions& o,
                                        InertiaFit* fit) {
  fit->mesh_check = io::CheckMesh(*o.mesh);
  TF_ASSIGN_OR_RETURN(RegionModel built,
                      BuildRegions(*o.mesh, o.density.regions, o.mesh_name, o.interrupt));
  auto model = std::make_shared<const RegionModel>(std::move(built));
  const RegionModel& regions = *model;
  InterruptPoll poll(o.interrupt);
  MethodOutput out;
  for (const std::string& n : regions.notes) out.notes.push_back(n);
  const GlsData gls = PrepareGls(s, o, &out.notes, &poll);
  if (poll.stopped()) return Interrupted();
  const int n = static_cast<int>(gls.kin.size());
  TF_ASSIGN_OR_RETURN(DensityBasis basis, MakeDensityBasis(gls, regions, o));
  out.scale = basis.parameter_scale;

  const int folds = std::clamp(o.density.folds, 2, std::max(2, n / 10));
  const bool choose = o.density.regularization < 0;
  DensityState st;
  st.pi = basis.pi_uniform;
  st.u = VectorXd::Ones(basis.K);
  st.lambda_rel = choose ? 0.0 : o.density.regularization;
  for (int round = 0; round < o.reweighting_rounds; ++round) {
    if (poll.Check()) return Interrupted();
    TF_RETURN_IF_ERROR(
        DensityRound(gls, basis, regions, o, round, folds, choose, &st, &out, &poll));
    if (o.progress) o.progress(0.9 * (round + 1) / o.reweighting_rounds);
  }
  out.pi = st.pi;
  out.iterations = st.qp.iterations;  // the fit's own solves (not the contradiction test's)
  out.samples_used = n;
  out.regularization = st.lambda_rel;
  out.regularization_rule =
      choose ? absl::StrCat("held-out time blocks (", folds, " folds)") : "given";
  out.densities.resize(basis.K);
  for (int r = 0; r < basis.K; ++r) out.densities[r] = basis.rho_ref * st.u(r);
  if (poll.Check()) return Interrupted();
  DensityCovariance(basis, st, &out);
  HeldOutContradiction(gls, basis, folds, &st, &out, &poll);
  MeshConsistency(gls, basis, &st, &out, &poll);
  ResidualRms(gls.kin, gls.wrench, st.pi, &poll, &out.rms_force, &out.rms_torque);
  if (poll.stopped()) return Interrupted();
  ReportDensity(std::move(model), o, &out, fit);
  return out;
}

}  // namespace tactforce::inertia::internal
