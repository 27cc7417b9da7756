// The phantom candidate: a reading that persists after unloading (GeoDEx's
// hysteresis failure, a phantom force that made a finger detach). On top of
// the current model, the reading gets c * exp(-(t - t_r) / decay) at every
// unloaded sample (reference <= the release level) after a release at t_r.
// The current model's residual is linear in c, so c is solved in closed form
// per decay; the decay is searched on a log grid and refined by golden
// section, all on the training block, and scored on the held-out block.
#include <algorithm>
#include <cmath>

#include "cause_selection.h"

namespace tactforce::audit::internal {

std::vector<double> PhantomProfile(const MeasuredData& d, double release_level, double decay) {
  const size_t n = d.t.size();
  std::vector<double> out(n, 0.0);
  size_t seg = 0;
  bool loaded = false;
  double t_release = 0;
  for (size_t i = 0; i < n; ++i) {
    if (seg < d.segment_starts.size() && static_cast<int>(i) == d.segment_starts[seg]) {
      loaded = false;  // a new trial: no release carried over
      ++seg;
    }
    if (d.reference[i] > release_level) {
      loaded = true;
      t_release = -1;
      continue;
    }
    if (!loaded) continue;
    if (t_release < 0 || i == 0 || d.reference[i - 1] > release_level) t_release = d.t[i];
    out[i] = std::exp(-(d.t[i] - t_release) / decay);
  }
  return out;
}

namespace {

struct PhantomScore {
  double coefficient = 0;
  double rss_drop = 0;  // training RSS reduction
};

// Least-squares coefficient of the profile on the training residual and the
// training RSS it removes.
PhantomScore ScoreDecay(const MeasuredData& d, const std::vector<double>& residual, int n_train, double release,
                        double decay) {
  const std::vector<double> p = PhantomProfile(d, release, decay);
  double rp = 0, pp = 0;
  for (int i = 0; i < n_train; ++i) {
    rp += residual[i] * p[i];
    pp += p[i] * p[i];
  }
  PhantomScore s;
  if (pp > 0) {
    s.coefficient = rp / pp;
    s.rss_drop = rp * rp / pp;
  }
  return s;
}

}  // namespace

PhantomFit FitPhantom(ChannelEvaluator& eng, const Selection& s) {
  const MeasuredData& d = eng.data();
  const int n = static_cast<int>(d.t.size()), n_train = eng.n_train();
  const std::vector<double>& g = eng.FullChannel(s.params);
  std::vector<double> residual(n);
  for (int i = 0; i < n; ++i) residual[i] = d.reading[i] - s.fit.a * g[i] - s.fit.b;
  // Only a positive force persists: the coefficient must have the gain's sign.
  auto value = [&](double log_decay) {
    const PhantomScore sc = ScoreDecay(d, residual, n_train, s.release_level, std::exp(log_decay));
    return sc.coefficient * s.fit.a > 0 ? sc.rss_drop : 0.0;
  };
  const double lo = std::log(0.02), hi = std::log(30.0);
  constexpr int kGrid = 24;
  int best = 0;
  double best_v = -1;
  for (int k = 0; k < kGrid; ++k) {
    const double v = value(lo + (hi - lo) * k / (kGrid - 1));
    if (v > best_v) best_v = v, best = k;
  }
  PhantomFit fit;
  if (!(best_v > 0)) return fit;
  // Golden section between the grid neighbours of the best.
  const double step = (hi - lo) / (kGrid - 1);
  double a = lo + step * std::max(0, best - 1), b = lo + step * std::min(kGrid - 1, best + 1);
  const double r = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = b - r * (b - a), x2 = a + r * (b - a), f1 = value(x1), f2 = value(x2);
  for (int it = 0; it < 20; ++it) {
    if (f1 > f2) b = x2, x2 = x1, f2 = f1, x1 = b - r * (b - a), f1 = value(x1);
    else a = x1, x1 = x2, f1 = f2, x2 = a + r * (b - a), f2 = value(x2);
  }
  const double log_decay = f1 > f2 ? x1 : x2;
  fit.decay = std::exp(log_decay);
  const PhantomScore sc = ScoreDecay(d, residual, n_train, s.release_level, fit.decay);
  if (!(sc.coefficient * s.fit.a > 0)) return fit;
  fit.coefficient = sc.coefficient;
  fit.force = sc.coefficient / s.fit.a;
  const std::vector<double> p = PhantomProfile(d, s.release_level, fit.decay);
  double rss = 0;
  for (int i = n_train; i < n; ++i) {
    const double e = residual[i] - fit.coefficient * p[i];
    rss += e * e;
  }
  fit.rss_heldout = rss;
  fit.bic = Bic(rss, n - n_train, s.k + 2);
  fit.ok = std::isfinite(fit.bic);
  return fit;
}

}  // namespace tactforce::audit::internal
