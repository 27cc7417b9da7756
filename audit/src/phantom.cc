// The phantom candidate: a reading that persists after unloading (GeoDEx's
// hysteresis failure, a phantom force that made a finger detach). On top of
// the current model, the reading gets c * exp(-(t - t_r) / decay) at every
// unloaded sample (reference <= the release level) after a release at t_r.
// The reading is linear in c, so c is solved in closed form
// with the gain and offset per decay; the decay is searched on a log grid and
// refined by golden section, all on the training block, and scored on the
// held-out block.
#include <algorithm>
#include <cmath>
#include <limits>

#include "Eigen/Dense"

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

// Reading ~ a g + b + c phantom, least squares on the training block (the
// phantom biases a gain/offset fitted without it, so all three are fitted).
struct PhantomScore {
  double a = 0, b = 0, c = 0;
  double rss_train = std::numeric_limits<double>::infinity();
};

PhantomScore ScoreDecay(const MeasuredData& d, const std::vector<double>& g, int n_train,
                        double release, double decay) {
  const std::vector<double> p = PhantomProfile(d, release, decay);
  Eigen::Matrix3d xtx = Eigen::Matrix3d::Zero();
  Eigen::Vector3d xty = Eigen::Vector3d::Zero();
  double yy = 0;
  for (int i = 0; i < n_train; ++i) {
    const Eigen::Vector3d x(g[i], 1.0, p[i]);
    xtx += x * x.transpose();
    xty += x * d.reading[i];
    yy += d.reading[i] * d.reading[i];
  }
  PhantomScore s;
  if (!(xtx(2, 2) > 0)) return s;
  const Eigen::Vector3d beta = xtx.ldlt().solve(xty);
  if (!beta.allFinite()) return s;
  s.a = beta[0], s.b = beta[1], s.c = beta[2];
  s.rss_train = std::max(0.0, yy - 2 * beta.dot(xty) + beta.dot(xtx * beta));
  return s;
}

}  // namespace

PhantomFit FitPhantom(ChannelEvaluator& eng, const Selection& s) {
  const MeasuredData& d = eng.data();
  const int n = static_cast<int>(d.t.size()), n_train = eng.n_train();
  const std::vector<double> g = eng.FullChannel(s.params);
  // Only a positive force persists: c must have the gain's sign.
  auto value = [&](double log_decay) {
    const PhantomScore sc = ScoreDecay(d, g, n_train, s.release_level, std::exp(log_decay));
    return sc.c * sc.a > 0 ? sc.rss_train : std::numeric_limits<double>::infinity();
  };
  const double lo = std::log(0.02), hi = std::log(30.0);
  constexpr int kGrid = 24;
  int best = -1;
  double best_v = std::numeric_limits<double>::infinity();
  for (int k = 0; k < kGrid; ++k) {
    const double v = value(lo + (hi - lo) * k / (kGrid - 1));
    if (v < best_v) best_v = v, best = k;
  }
  PhantomFit fit;
  if (best < 0) return fit;
  // Golden section between the grid neighbours of the best.
  const double step = (hi - lo) / (kGrid - 1);
  double a = lo + step * std::max(0, best - 1), b = lo + step * std::min(kGrid - 1, best + 1);
  const double r = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = b - r * (b - a), x2 = a + r * (b - a), f1 = value(x1), f2 = value(x2);
  for (int it = 0; it < 20; ++it) {
    if (f1 < f2)
      b = x2, x2 = x1, f2 = f1, x1 = b - r * (b - a), f1 = value(x1);
    else
      a = x1, x1 = x2, f1 = f2, x2 = a + r * (b - a), f2 = value(x2);
  }
  fit.decay = std::exp(f1 < f2 ? x1 : x2);
  if (std::min(f1, f2) > best_v) fit.decay = std::exp(lo + step * best);
  const PhantomScore sc = ScoreDecay(d, g, n_train, s.release_level, fit.decay);
  if (!(sc.c * sc.a > 0)) return fit;
  fit.coefficient = sc.c;
  fit.force = sc.c / sc.a;
  const std::vector<double> p = PhantomProfile(d, s.release_level, fit.decay);
  double rss = 0;
  for (int i = n_train; i < n; ++i) {
    const double e = d.reading[i] - sc.a * g[i] - sc.b - sc.c * p[i];
    rss += e * e;
  }
  fit.rss_heldout = rss;
  fit.bic = Bic(rss, n - n_train, s.k + 2);  // force and decay
  fit.ok = std::isfinite(fit.bic);
  return fit;
}

}  // namespace tactforce::audit::internal
