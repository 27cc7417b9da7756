// Prandtl-Ishlinskii hysteresis fitted by non-negative least squares: on a
// fixed grid of play radii (r = 0, the identity, plus 12 radii geometric in
// [0.002 R, 0.1 R]) the channel output is sum_k w_k P_k, linear in the
// weights when what follows the hysteresis in the chain is affine (+ drift),
// so the weights (>= 0, with the gain's sign and an offset) are the NNLS
// solution on the training block (Lawson-Hanson on the normal equations).
// Zero weights are pruned, the rest normalised to sum 1; with a static
// nonlinearity or other named effects in the model the weights are then
// refined jointly with them (LN_SBPLX, bounds [0, 1]).
#include <algorithm>
#include <vector>

#include "Eigen/Dense"
#include "effect_fit.h"

namespace tactforce::audit::internal {

using sim::EffectParams;

namespace {

// Solution z of the unconstrained least squares on the passive set (zero
// elsewhere), with a tiny ridge: neighbouring play operators are nearly
// collinear.
std::vector<double> SolvePassive(const Eigen::MatrixXd& G, const Eigen::VectorXd& h,
                                 const std::vector<bool>& passive) {
  const int m = static_cast<int>(h.size());
  std::vector<int> idx;
  for (int j = 0; j < m; ++j)
    if (passive[j]) idx.push_back(j);
  std::vector<double> z(m, 0.0);
  if (idx.empty()) return z;
  Eigen::MatrixXd Gp(idx.size(), idx.size());
  Eigen::VectorXd hp(idx.size());
  for (size_t a = 0; a < idx.size(); ++a) {
    hp[a] = h[idx[a]];
    for (size_t b = 0; b < idx.size(); ++b) Gp(a, b) = G(idx[a], idx[b]);
  }
  Gp.diagonal().array() += 1e-12 * std::max(1.0, Gp.diagonal().maxCoeff());
  Eigen::VectorXd zp = Gp.ldlt().solve(hp);
  for (size_t a = 0; a < idx.size(); ++a) z[idx[a]] = zp[a];
  return z;
}

// Lawson-Hanson inner loop: moves c towards the passive-set solution until it
// is feasible, dropping the variables that reach zero.
void ConstrainToPassive(const Eigen::MatrixXd& G, const Eigen::VectorXd& h,
                        std::vector<bool>* passive, std::vector<double>* c) {
  const int m = static_cast<int>(h.size());
  for (int inner = 0; inner < 3 * m; ++inner) {
    const std::vector<double> z = SolvePassive(G, h, *passive);
    bool feasible = true;
    for (int j = 0; j < m; ++j)
      if ((*passive)[j] && z[j] <= 0) feasible = false;
    if (feasible) {
      *c = z;
      return;
    }
    double alpha = 1;
    for (int j = 0; j < m; ++j)
      if ((*passive)[j] && z[j] <= 0) alpha = std::min(alpha, (*c)[j] / ((*c)[j] - z[j]));
    for (int j = 0; j < m; ++j) {
      (*c)[j] += alpha * (z[j] - (*c)[j]);
      if ((*passive)[j] && (*c)[j] <= 1e-15) {
        (*passive)[j] = false;
        (*c)[j] = 0;
      }
    }
  }
}

// Non-negative least squares min |X c - y|^2, c >= 0, in normal-equation form
// (G = X'X, h = X'y; Lawson-Hanson active set). Small problems only.
std::vector<double> Nnls(const Eigen::MatrixXd& G, const Eigen::VectorXd& h) {
  const int m = static_cast<int>(h.size());
  std::vector<double> c(m, 0.0);
  std::vector<bool> passive(m, false);
  const double tol = 1e-12 * std::max(1.0, G.diagonal().cwiseAbs().maxCoeff());
  for (int outer = 0; outer < 3 * m; ++outer) {
    // Gradient of -0.5|Xc-y|^2: w = h - G c.
    Eigen::VectorXd cv = Eigen::Map<Eigen::VectorXd>(c.data(), m);
    Eigen::VectorXd w = h - G * cv;
    int jmax = -1;
    double wmax = tol;
    for (int j = 0; j < m; ++j)
      if (!passive[j] && w[j] > wmax) {
        wmax = w[j];
        jmax = j;
      }
    if (jmax < 0) break;
    passive[jmax] = true;
    ConstrainToPassive(G, h, &passive, &c);
  }
  return c;
}

// Normal equations (G = X'X, h = X'y) of the reading on the channel outputs
// with a single play operator of each radius, columns and reading centred
// (the intercept).
void PlayNormalEquations(ChannelEvaluator& eng, const EffectParams& current,
                         const std::vector<double>& radii, Eigen::MatrixXd* G, Eigen::VectorXd* h) {
  const int m = static_cast<int>(radii.size());
  const int n = eng.n_train();
  const std::vector<double>& y = eng.reading();
  Eigen::MatrixXd X(n, m);
  for (int k = 0; k < m; ++k) {
    EffectParams p = current;
    p.pi_thresholds.clear();
    p.pi_weights.clear();
    p.hysteresis_width = 2 * radii[k];
    const std::vector<double>& g = eng.TrainChannel(p);
    for (int i = 0; i < n; ++i) X(i, k) = g[i];
  }
  Eigen::VectorXd yv(n);
  for (int i = 0; i < n; ++i) yv[i] = y[i];
  const double ymean = yv.mean();
  yv.array() -= ymean;
  for (int k = 0; k < m; ++k) X.col(k).array() -= X.col(k).mean();
  *G = X.transpose() * X;
  *h = X.transpose() * yv;
}

// The PI hysteresis of the NNLS weights c on `radii` (weights above 1e-6 of
// their sum, normalised) in place of current's hysteresis; false when only
// the identity (or nothing) is left.
bool PiFromWeights(const EffectParams& current, const std::vector<double>& radii,
                   const std::vector<double>& c, EffectParams* p) {
  double csum = 0;
  for (double v : c) csum += v;
  if (!(csum > 0)) return false;
  *p = current;
  p->hysteresis_width = 0;
  p->pi_thresholds.clear();
  p->pi_weights.clear();
  for (size_t k = 0; k < radii.size(); ++k)
    if (c[k] > 1e-6 * csum) {
      p->pi_thresholds.push_back(radii[k]);
      p->pi_weights.push_back(c[k]);
    }
  if (p->pi_thresholds.empty() || (p->pi_thresholds.size() == 1 && p->pi_thresholds[0] == 0))
    return false;
  NormaliseWeights(&p->pi_weights);
  return true;
}

}  // namespace

FitResult FitPrandtlIshlinskii(ChannelEvaluator& eng, const EffectParams& current,
                               const std::vector<Effect>& selected, const RunStats& st,
                               const AuditOptions& o) {
  std::vector<double> radii = {0.0};
  for (double r : GeometricGrid(0.002 * st.range, 0.1 * st.range, 12)) radii.push_back(r);
  Eigen::MatrixXd G;
  Eigen::VectorXd h;
  PlayNormalEquations(eng, current, radii, &G, &h);
  FitResult best;
  best.p = current;
  best.rss_train = eng.Evaluate(current, false).rss_train;
  for (double sign : {1.0, -1.0}) {
    EffectParams p;
    if (!PiFromWeights(current, radii, Nnls(G, sign * h), &p)) continue;
    const double rss = eng.Evaluate(p, false).rss_train;
    if (rss < best.rss_train) {
      best.rss_train = rss;
      best.p = p;
    }
  }
  if (best.p.pi_thresholds.empty()) return best;
  const bool static_after = best.p.curvature != 0 || best.p.power_exponent > 0 ||
                            best.p.threshold > 0 || best.p.saturation > 0;
  if (static_after || !selected.empty()) {
    std::vector<Slot> joint =
        SlotsFor(Effect::kHysteresis, st, o, Form::kPrandtlIshlinskii, &best.p);
    for (Slot& sl : SelectedSlots(selected, best.p, st, o, nullptr)) joint.push_back(std::move(sl));
    const int evals = o.max_evaluations * (1 + static_cast<int>(selected.size()));
    FitResult r = PolishThreshold(eng, Refine(eng, best.p, joint, false, evals, 0.05), st);
    if (r.rss_train < best.rss_train) best = r;
    NormaliseWeights(&best.p.pi_weights);
  }
  return best;
}

}  // namespace tactforce::audit::internal
