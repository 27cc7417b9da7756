#include <algorithm>
#include <cmath>
#include <limits>
#include <nlopt.hpp>

#include "Eigen/Dense"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "audit_internal.h"
#include "tactforce/audit/audit.h"

namespace tactforce::audit {

using sim::ChannelInput;
using sim::EffectParams;

const char* EffectName(Effect e) {
  switch (e) {
    case Effect::kDeadzone: return "deadzone";
    case Effect::kSaturation: return "saturation";
    case Effect::kNonlinearity: return "nonlinearity";
    case Effect::kHysteresis: return "hysteresis";
    case Effect::kDelay: return "delay";
    case Effect::kLag: return "lag";
    case Effect::kDrift: return "drift";
    case Effect::kCrosstalk: return "crosstalk";
  }
  return "?";
}

const std::vector<Effect>& AllEffects() {
  static const std::vector<Effect> all = {Effect::kDeadzone, Effect::kSaturation, Effect::kNonlinearity,
                                          Effect::kHysteresis, Effect::kDelay,     Effect::kLag,
                                          Effect::kDrift,      Effect::kCrosstalk};
  return all;
}

absl::StatusOr<Effect> ParseEffect(const std::string& name) {
  for (Effect e : AllEffects())
    if (name == EffectName(e)) return e;
  return absl::InvalidArgumentError(absl::StrCat(
      "effect: unknown '", name,
      "' (expected deadzone, saturation, nonlinearity, hysteresis, delay, lag, drift or crosstalk)"));
}

namespace {

struct Slot {
  std::string field;
  double EffectParams::*ptr;  // null for a Prandtl-Ishlinskii weight
  double lo, hi;
  std::vector<double> grid;  // coarse start values (sorted)
  int pi_index = -1;         // >= 0: pi_weights[pi_index]
};

double Get(const EffectParams& p, const Slot& s) { return s.pi_index >= 0 ? p.pi_weights[s.pi_index] : p.*(s.ptr); }
void Set(EffectParams& p, const Slot& s, double v) {
  if (s.pi_index >= 0) p.pi_weights[s.pi_index] = v;
  else p.*(s.ptr) = v;
}

// The functional form of an effect (hysteresis and nonlinearity have two).
enum class Form { kOnly, kPlay, kPrandtlIshlinskii, kQuadratic, kPowerLaw };

const char* FormName(Form f) {
  switch (f) {
    case Form::kOnly: return "";
    case Form::kPlay: return "play";
    case Form::kPrandtlIshlinskii: return "prandtl_ishlinskii";
    case Form::kQuadratic: return "quadratic";
    case Form::kPowerLaw: return "power_law";
  }
  return "";
}

Form DefaultForm(Effect e) {
  if (e == Effect::kHysteresis) return Form::kPlay;
  if (e == Effect::kNonlinearity) return Form::kQuadratic;
  return Form::kOnly;
}

// The form an effect has in the parameters p.
Form FormOf(Effect e, const EffectParams& p) {
  if (e == Effect::kHysteresis) return p.pi_thresholds.empty() ? Form::kPlay : Form::kPrandtlIshlinskii;
  if (e == Effect::kNonlinearity) return p.power_exponent > 0 ? Form::kPowerLaw : Form::kQuadratic;
  return Form::kOnly;
}

struct Stats {
  double fmin, fmax, range, fabsmax, duration, dt;
  bool has_shear;
};

std::vector<double> Geom(double a, double b, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = a * std::pow(b / a, n == 1 ? 0.0 : double(i) / (n - 1));
  return v;
}
std::vector<double> Lin(double a, double b, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = a + (b - a) * (n == 1 ? 0.0 : double(i) / (n - 1));
  return v;
}

bool IsSmooth(Effect e) {
  return e == Effect::kNonlinearity || e == Effect::kDrift || e == Effect::kCrosstalk;
}

std::vector<Slot> SlotsFor(Effect e, const Stats& s, const AuditOptions& o, Form form = Form::kOnly,
                           const EffectParams* p = nullptr) {
  const double R = s.range;
  if (form == Form::kPowerLaw)
    return {{"power_exponent", &EffectParams::power_exponent, 0.2, 4.0, {0.5, 0.67, 0.8, 0.9, 1.1, 1.25, 1.5, 2.0}}};
  if (form == Form::kPrandtlIshlinskii) {
    std::vector<Slot> v;
    if (p)
      for (size_t k = 0; k < p->pi_weights.size(); ++k)
        v.push_back({absl::StrCat("pi_weights[", k, "]"), nullptr, 0.0, 1.0, {}, static_cast<int>(k)});
    return v;
  }
  switch (e) {
    case Effect::kDeadzone: {
      std::vector<double> g;
      for (double x : Geom(0.003 * R, 0.5 * R, 24)) g.push_back(s.fmin + x);
      return {{"threshold", &EffectParams::threshold, std::max(0.0, s.fmin), s.fmin + 0.5 * R, g},
              {"threshold_shift", &EffectParams::threshold_shift, 0, 1, {0, 1}}};
    }
    case Effect::kSaturation:
      return {{"saturation", &EffectParams::saturation, s.fmin + 0.2 * R, s.fmax, Lin(s.fmin + 0.2 * R, s.fmax, 24)}};
    case Effect::kNonlinearity:
      return {{"curvature", &EffectParams::curvature, -0.5, 0.5, Lin(-0.3, 0.3, 7)}};
    case Effect::kHysteresis:
      return {{"hysteresis_width", &EffectParams::hysteresis_width, 0, 0.3 * R, Geom(0.002 * R, 0.3 * R, 24)}};
    case Effect::kDelay: {
      std::vector<double> g;
      const double lo = std::min(0.25 * s.dt, 0.5 * o.max_delay);
      for (double x : Geom(lo, o.max_delay, 12)) {
        g.push_back(x);
        g.push_back(-x);
      }
      g.push_back(0);
      std::sort(g.begin(), g.end());
      return {{"delay", &EffectParams::delay, -o.max_delay, o.max_delay, g}};
    }
    case Effect::kLag: {
      const double lo = std::min(0.25 * s.dt, 0.5 * o.max_lag);
      return {{"lag", &EffectParams::lag, 0, o.max_lag, Geom(lo, o.max_lag, 24)}};
    }
    case Effect::kDrift: {
      const double m = R / std::max(s.duration, 1e-9);
      return {{"drift", &EffectParams::drift, -m, m, Lin(-0.3 * m, 0.3 * m, 7)}};
    }
    case Effect::kCrosstalk:
      return {{"crosstalk", &EffectParams::crosstalk, -1, 1, Lin(-0.6, 0.6, 7)}};
  }
  return {};
}

struct Eval {
  double a = 0, b = 0, rss_train = 0, rss_heldout = 0;
};

class Engine {
 public:
  Engine(const MeasuredData& d, int n_train) : d_(d), n_train_(n_train) {
    in_.t = d.t.data();
    in_.force = d.reference.data();
    in_.shear = d.shear.empty() ? nullptr : d.shear.data();
    in_.segment_starts = &d.segment_starts;
    in_.t0 = d.t.front();
  }

  Eval Evaluate(const EffectParams& p, bool heldout) {
    ++evaluations;
    ChannelInput in = in_;
    in.n = heldout ? static_cast<int>(d_.t.size()) : n_train_;
    sim::ApplyChannel(p, in, &g_);
    double sg = 0, sy = 0, sgg = 0, sgy = 0, syy = 0;
    const double* y = d_.reading.data();
    for (int i = 0; i < n_train_; ++i) {
      const double g = g_[i];
      sg += g;
      sy += y[i];
      sgg += g * g;
      sgy += g * y[i];
      syy += y[i] * y[i];
    }
    const double n = n_train_;
    const double vg = sgg - sg * sg / n;
    const double cgy = sgy - sg * sy / n;
    const double vy = syy - sy * sy / n;
    Eval ev;
    if (vg > 1e-12 * std::max(1.0, sgg)) {
      ev.a = cgy / vg;
      ev.b = (sy - ev.a * sg) / n;
      ev.rss_train = std::max(0.0, vy - cgy * cgy / vg);
    } else {
      ev.a = 0;
      ev.b = sy / n;
      ev.rss_train = std::max(0.0, vy);
    }
    if (heldout) {
      double r = 0;
      for (size_t i = n_train_; i < d_.t.size(); ++i) {
        const double e = y[i] - ev.a * g_[i] - ev.b;
        r += e * e;
      }
      ev.rss_heldout = r;
    }
    return ev;
  }

  // Force-domain channel output on the training block.
  const std::vector<double>& TrainChannel(const EffectParams& p) {
    ChannelInput in = in_;
    in.n = n_train_;
    sim::ApplyChannel(p, in, &g_);
    return g_;
  }

  std::vector<double> Predict(const EffectParams& p, double a, double b) {
    ChannelInput in = in_;
    in.n = static_cast<int>(d_.t.size());
    std::vector<double> out;
    sim::ApplyChannel(p, in, &out);
    for (double& v : out) v = a * v + b;
    return out;
  }

  int n_train() const { return n_train_; }
  const std::vector<double>& train_reading() const { return d_.reading; }  // first n_train() are training
  long evaluations = 0;

 private:
  const MeasuredData& d_;
  int n_train_;
  sim::ChannelInput in_;
  std::vector<double> g_;
};

struct FitResult {
  EffectParams p;
  double rss_train = std::numeric_limits<double>::infinity();
};

// NLopt local refinement over the given slots (normalised to [0,1]).
FitResult Refine(Engine& eng, const EffectParams& start, const std::vector<Slot>& slots, bool smooth,
                 int max_evaluations, double step) {
  FitResult best;
  best.p = start;
  best.rss_train = eng.Evaluate(start, false).rss_train;
  if (slots.empty() || max_evaluations <= 0) return best;
  const int k = static_cast<int>(slots.size());
  struct Ctx {
    Engine* eng;
    const std::vector<Slot>* slots;
    EffectParams base;
    FitResult* best;
  } ctx{&eng, &slots, start, &best};
  auto to_params = [](const Ctx& c, const std::vector<double>& x) {
    EffectParams p = c.base;
    for (size_t i = 0; i < c.slots->size(); ++i) {
      const Slot& s = (*c.slots)[i];
      Set(p, s, s.lo + std::clamp(x[i], 0.0, 1.0) * (s.hi - s.lo));
    }
    return p;
  };
  auto objective = [](const std::vector<double>& x, std::vector<double>& grad, void* data) -> double {
    auto* c = static_cast<Ctx*>(data);
    EffectParams p = c->base;
    for (size_t i = 0; i < c->slots->size(); ++i) {
      const Slot& s = (*c->slots)[i];
      Set(p, s, s.lo + std::clamp(x[i], 0.0, 1.0) * (s.hi - s.lo));
    }
    const double rss = c->eng->Evaluate(p, false).rss_train;
    if (rss < c->best->rss_train) {
      c->best->rss_train = rss;
      c->best->p = p;
    }
    return rss;
  };
  std::vector<double> x(k), lo(k, 0.0), hi(k, 1.0), dx(k, step);
  for (int i = 0; i < k; ++i) {
    const Slot& s = slots[i];
    x[i] = s.hi > s.lo ? std::clamp((Get(start, s) - s.lo) / (s.hi - s.lo), 0.0, 1.0) : 0.0;
    if (x[i] + step > 1) dx[i] = -step;
  }
  try {
    nlopt::opt opt(smooth ? nlopt::LN_BOBYQA : nlopt::LN_SBPLX, k);
    opt.set_lower_bounds(lo);
    opt.set_upper_bounds(hi);
    opt.set_min_objective(objective, &ctx);
    opt.set_maxeval(max_evaluations);
    opt.set_xtol_abs(1e-5);
    opt.set_ftol_rel(1e-9);
    std::vector<double> dxa(k);
    for (int i = 0; i < k; ++i) dxa[i] = std::abs(dx[i]);
    opt.set_initial_step(dxa);
    double f = 0;
    opt.optimize(x, f);
  } catch (const std::exception&) {
    // roundoff / forced stop: keep the best point seen (tracked in objective)
  }
  (void)to_params;
  return best;
}

// The RSS is piecewise constant in the threshold (it only changes when the
// threshold passes a pre-threshold value u_i), and with an activation jump a
// threshold a little off misclassifies crossing samples by ~threshold. Scan
// the exact breakpoints near the estimate and take the middle of the best
// flat interval.
FitResult PolishThreshold(Engine& eng, const FitResult& in, const Stats& st) {
  if (!(in.p.threshold > 0)) return in;
  EffectParams pre = in.p;
  pre.threshold = 0;
  pre.saturation = 0;
  pre.drift = 0;
  std::vector<double> u = eng.TrainChannel(pre);
  const double th = in.p.threshold, w = 0.05 * st.range;
  std::vector<double> near;
  for (double v : u)
    if (std::abs(v - th) <= w) near.push_back(v);
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  if (near.size() < 2) return in;
  // At most ~120 breakpoints, centred on the estimate.
  auto it = std::lower_bound(near.begin(), near.end(), th);
  const long c = it - near.begin();
  const long lo = std::max(0L, c - 60), hi = std::min<long>(near.size() - 1, c + 60);
  FitResult best = in;
  std::vector<std::pair<double, double>> scores;  // (threshold, rss)
  for (long k = lo; k < hi; ++k) {
    EffectParams q = in.p;
    q.threshold = 0.5 * (near[k] + near[k + 1]);
    if (q.threshold <= 0) continue;
    scores.emplace_back(q.threshold, eng.Evaluate(q, false).rss_train);
  }
  if (scores.empty()) return in;
  double min_rss = in.rss_train;
  for (const auto& sc : scores) min_rss = std::min(min_rss, sc.second);
  // Differences below 1 % of one sample's residual variance are ties (a tiny
  // threshold_shift tilts a plateau by far less than that).
  const double tol = 0.01 * std::max(min_rss, 1e-300) / eng.n_train();
  // Runs of consecutive breakpoints at the minimum; take the run closest to
  // the current threshold (its own plateau when it is already optimal).
  long best_first = -1, best_last = -1;
  double best_dist = std::numeric_limits<double>::infinity();
  for (size_t k = 0; k < scores.size();) {
    if (scores[k].second > min_rss + tol) {
      ++k;
      continue;
    }
    size_t j = k;
    while (j + 1 < scores.size() && scores[j + 1].second <= min_rss + tol) ++j;
    const double a = scores[k].first, b = scores[j].first;
    const double dist = th < a ? a - th : (th > b ? th - b : 0.0);
    if (dist < best_dist) {
      best_dist = dist;
      best_first = static_cast<long>(k);
      best_last = static_cast<long>(j);
    }
    k = j + 1;
  }
  if (best_first < 0) return in;
  best.p.threshold = 0.5 * (scores[best_first].first + scores[best_last].first);
  best.rss_train = eng.Evaluate(best.p, false).rss_train;
  if (best.rss_train > min_rss + tol) {  // numerical corner: take a scanned minimum
    best.p.threshold = scores[best_first].first;
    best.rss_train = scores[best_first].second;
  }
  return best.rss_train <= in.rss_train + tol ? best : in;
}

// Fits one effect's parameters on top of `current`: coarse grid over its
// first parameter (all combinations with the grid of the second), a finer
// grid around the best, then an NLopt refinement.
// Slots of the effects named so far, in their current forms.
std::vector<Slot> SelectedSlots(const std::vector<Effect>& selected, const EffectParams& p, const Stats& st,
                                const AuditOptions& o, bool* smooth) {
  std::vector<Slot> v;
  for (Effect s : selected) {
    const Form f = FormOf(s, p);
    for (Slot& sl : SlotsFor(s, st, o, f, &p)) v.push_back(std::move(sl));
    // PI weights enter non-smoothly through the play operators.
    if (smooth) *smooth = *smooth && IsSmooth(s) && f != Form::kPrandtlIshlinskii;
  }
  return v;
}

FitResult FitEffect(Engine& eng, Effect e, const EffectParams& current, const std::vector<Effect>& selected,
                    const Stats& st, const AuditOptions& o, Form form = Form::kOnly) {
  const std::vector<Slot> slots = SlotsFor(e, st, o, form);
  FitResult best;
  best.p = current;
  auto consider = [&](const EffectParams& p) {
    const double rss = eng.Evaluate(p, false).rss_train;
    if (rss < best.rss_train) {
      best.rss_train = rss;
      best.p = p;
    }
  };
  const Slot& s0 = slots[0];
  std::vector<std::vector<double>> second;
  if (slots.size() > 1) second.push_back(slots[1].grid);
  int best_i = 0;
  for (size_t i = 0; i < s0.grid.size(); ++i) {
    EffectParams p = current;
    Set(p, s0, s0.grid[i]);
    if (second.empty()) {
      const double before = best.rss_train;
      consider(p);
      if (best.rss_train < before) best_i = static_cast<int>(i);
    } else {
      for (double v : second[0]) {
        EffectParams q = p;
        Set(q, slots[1], v);
        const double before = best.rss_train;
        consider(q);
        if (best.rss_train < before) best_i = static_cast<int>(i);
      }
    }
  }
  if (!IsSmooth(e) && s0.grid.size() > 2) {
    const double a = s0.grid[std::max(0, best_i - 1)];
    const double b = s0.grid[std::min<int>(s0.grid.size() - 1, best_i + 1)];
    const EffectParams base = best.p;
    for (double v : Lin(a, b, 12)) {
      EffectParams p = base;
      Set(p, s0, v);
      consider(p);
    }
  }
  // Refine the new effect jointly with the effects named before it (an
  // earlier effect may have absorbed part of this one, e.g. delay + lag).
  std::vector<Slot> joint = slots;
  bool smooth = IsSmooth(e);
  for (Slot& sl : SelectedSlots(selected, best.p, st, o, &smooth)) joint.push_back(std::move(sl));
  const int evals = o.max_evaluations * (1 + static_cast<int>(selected.size()));
  FitResult r = Refine(eng, best.p, joint, smooth, evals, smooth ? 0.1 : 0.02);
  return PolishThreshold(eng, r.rss_train <= best.rss_train ? r : best, st);
}

// Non-negative least squares min |X c - y|^2, c >= 0, in normal-equation form
// (G = X'X, h = X'y; Lawson-Hanson active set). Small problems only.
std::vector<double> Nnls(const Eigen::MatrixXd& G, const Eigen::VectorXd& h) {
  const int m = static_cast<int>(h.size());
  std::vector<double> c(m, 0.0);
  std::vector<bool> passive(m, false);
  const double tol = 1e-12 * std::max(1.0, G.diagonal().cwiseAbs().maxCoeff());
  auto solve_passive = [&](std::vector<double>* z) {
    std::vector<int> idx;
    for (int j = 0; j < m; ++j)
      if (passive[j]) idx.push_back(j);
    z->assign(m, 0.0);
    if (idx.empty()) return;
    Eigen::MatrixXd Gp(idx.size(), idx.size());
    Eigen::VectorXd hp(idx.size());
    for (size_t a = 0; a < idx.size(); ++a) {
      hp[a] = h[idx[a]];
      for (size_t b = 0; b < idx.size(); ++b) Gp(a, b) = G(idx[a], idx[b]);
    }
    // Tiny ridge: neighbouring play operators are nearly collinear.
    Gp.diagonal().array() += 1e-12 * std::max(1.0, Gp.diagonal().maxCoeff());
    Eigen::VectorXd zp = Gp.ldlt().solve(hp);
    for (size_t a = 0; a < idx.size(); ++a) (*z)[idx[a]] = zp[a];
  };
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
    for (int inner = 0; inner < 3 * m; ++inner) {
      std::vector<double> z;
      solve_passive(&z);
      bool feasible = true;
      for (int j = 0; j < m; ++j)
        if (passive[j] && z[j] <= 0) feasible = false;
      if (feasible) {
        c = z;
        break;
      }
      double alpha = 1;
      for (int j = 0; j < m; ++j)
        if (passive[j] && z[j] <= 0) alpha = std::min(alpha, c[j] / (c[j] - z[j]));
      for (int j = 0; j < m; ++j) {
        c[j] += alpha * (z[j] - c[j]);
        if (passive[j] && c[j] <= 1e-15) {
          passive[j] = false;
          c[j] = 0;
        }
      }
    }
  }
  return c;
}

// Prandtl-Ishlinskii hysteresis on a fixed grid of play radii (r = 0, the
// identity, plus 12 radii geometric in [0.002 R, 0.1 R]): the channel output
// is sum_k w_k P_k, linear in the weights when what follows the hysteresis in
// the chain is affine (+ drift), so the weights (>= 0, with the gain's sign
// and an offset) are the NNLS solution on the training block. Zero weights
// are pruned, the rest normalised to sum 1; with a static nonlinearity or
// other named effects in the model the weights are then refined jointly with
// them (LN_SBPLX, bounds [0, 1]).
FitResult FitPrandtlIshlinskii(Engine& eng, const EffectParams& current, const std::vector<Effect>& selected,
                               const Stats& st, const AuditOptions& o) {
  std::vector<double> radii = {0.0};
  for (double r : Geom(0.002 * st.range, 0.1 * st.range, 12)) radii.push_back(r);
  const int m = static_cast<int>(radii.size());
  const int n = eng.n_train();
  const std::vector<double>& y = eng.train_reading();
  Eigen::MatrixXd X(n, m);
  for (int k = 0; k < m; ++k) {
    EffectParams p = current;
    p.pi_thresholds.clear();
    p.pi_weights.clear();
    p.hysteresis_width = 2 * radii[k];
    const std::vector<double>& g = eng.TrainChannel(p);
    for (int i = 0; i < n; ++i) X(i, k) = g[i];
  }
  // Intercept: centre the columns and the reading.
  Eigen::VectorXd yv(n);
  for (int i = 0; i < n; ++i) yv[i] = y[i];
  const double ymean = yv.mean();
  yv.array() -= ymean;
  for (int k = 0; k < m; ++k) X.col(k).array() -= X.col(k).mean();
  const Eigen::MatrixXd G = X.transpose() * X;
  const Eigen::VectorXd h = X.transpose() * yv;
  FitResult best;
  best.p = current;
  best.rss_train = eng.Evaluate(current, false).rss_train;
  for (double sign : {1.0, -1.0}) {
    std::vector<double> c = Nnls(G, sign * h);
    double csum = 0;
    for (double v : c) csum += v;
    if (!(csum > 0)) continue;
    EffectParams p = current;
    p.hysteresis_width = 0;
    p.pi_thresholds.clear();
    p.pi_weights.clear();
    for (int k = 0; k < m; ++k)
      if (c[k] > 1e-6 * csum) {
        p.pi_thresholds.push_back(radii[k]);
        p.pi_weights.push_back(c[k]);
      }
    if (p.pi_thresholds.empty() || (p.pi_thresholds.size() == 1 && p.pi_thresholds[0] == 0)) continue;
    double ws = 0;
    for (double w : p.pi_weights) ws += w;
    for (double& w : p.pi_weights) w /= ws;
    const double rss = eng.Evaluate(p, false).rss_train;
    if (rss < best.rss_train) {
      best.rss_train = rss;
      best.p = p;
    }
  }
  if (best.p.pi_thresholds.empty()) return best;
  const bool static_after = best.p.curvature != 0 || best.p.power_exponent > 0 || best.p.threshold > 0 ||
                            best.p.saturation > 0;
  if (static_after || !selected.empty()) {
    std::vector<Slot> joint = SlotsFor(Effect::kHysteresis, st, o, Form::kPrandtlIshlinskii, &best.p);
    for (Slot& sl : SelectedSlots(selected, best.p, st, o, nullptr)) joint.push_back(std::move(sl));
    const int evals = o.max_evaluations * (1 + static_cast<int>(selected.size()));
    FitResult r = PolishThreshold(eng, Refine(eng, best.p, joint, false, evals, 0.05), st);
    if (r.rss_train < best.rss_train) best = r;
    double ws = 0;
    for (double w : best.p.pi_weights) ws += w;
    if (ws > 0)
      for (double& w : best.p.pi_weights) w /= ws;
  }
  return best;
}

double Bic(double rss, int n, int k) {
  return n * std::log(std::max(rss, 1e-300) / n) + k * std::log(static_cast<double>(n));
}

// Parameters an effect adds to the model (BIC's k): a PI hysteresis counts
// one per active play operator.
int NumParams(Effect e, const EffectParams& p) {
  if (e == Effect::kDeadzone) return 2;
  if (e == Effect::kHysteresis && !p.pi_thresholds.empty()) return static_cast<int>(p.pi_thresholds.size());
  return 1;
}

// Maximal loop width of a PI hysteresis (normalised weights): 2 sum w_k r_k.
double PiLoopWidth(const EffectParams& p) {
  double ws = 0, wr = 0;
  for (size_t k = 0; k < p.pi_weights.size() && k < p.pi_thresholds.size(); ++k) {
    ws += p.pi_weights[k];
    wr += p.pi_weights[k] * p.pi_thresholds[k];
  }
  return ws > 0 ? 2 * wr / ws : 0;
}

std::map<std::string, double> ParamsOf(Effect e, const EffectParams& p, const Stats& st, const AuditOptions& o) {
  std::map<std::string, double> m;
  const Form f = FormOf(e, p);
  if (f == Form::kPrandtlIshlinskii) {
    m["loop_width"] = PiLoopWidth(p);
    m["operators"] = static_cast<double>(p.pi_thresholds.size());
    return m;
  }
  for (const Slot& s : SlotsFor(e, st, o, f, &p)) m[s.field] = Get(p, s);
  if (e == Effect::kNonlinearity) m["full_scale"] = p.full_scale;
  return m;
}

std::map<std::string, std::vector<double>> ArrayParamsOf(Effect e, const EffectParams& p) {
  std::map<std::string, std::vector<double>> m;
  if (FormOf(e, p) == Form::kPrandtlIshlinskii) {
    m["pi_thresholds"] = p.pi_thresholds;
    double ws = 0;
    for (double w : p.pi_weights) ws += w;
    std::vector<double> w = p.pi_weights;
    if (ws > 0)
      for (double& x : w) x /= ws;
    m["pi_weights"] = w;
  }
  return m;
}

// 1-sigma from the conditional Delta-RSS = sigma^2 interval of each parameter.
double Uncertainty(Engine& eng, const EffectParams& p, const Slot& s, double rss0, double sigma2) {
  const double x0 = Get(p, s);
  const double width = s.hi - s.lo;
  double sides[2];
  int found = 0;
  for (int dir = 0; dir < 2; ++dir) {
    const double sign = dir == 0 ? 1 : -1;
    const double limit = dir == 0 ? s.hi - x0 : x0 - s.lo;
    double lo = 0, hi = std::min(limit, 1e-4 * width);
    bool ok = false;
    while (hi <= limit && hi > 0) {
      EffectParams q = p;
      Set(q, s, x0 + sign * hi);
      if (eng.Evaluate(q, false).rss_train - rss0 >= sigma2) {
        ok = true;
        break;
      }
      lo = hi;
      if (hi >= limit) break;
      hi = std::min(limit, hi * 2.5);
    }
    if (!ok) {
      sides[dir] = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    for (int it = 0; it < 14; ++it) {
      const double mid = 0.5 * (lo + hi);
      EffectParams q = p;
      Set(q, s, x0 + sign * mid);
      if (eng.Evaluate(q, false).rss_train - rss0 >= sigma2) hi = mid;
      else lo = mid;
    }
    sides[dir] = 0.5 * (lo + hi);
    ++found;
  }
  if (found == 2) return 0.5 * (sides[0] + sides[1]);
  if (found == 1) return std::isnan(sides[0]) ? sides[1] : sides[0];
  return width;  // not constrained within bounds
}

}  // namespace

std::vector<std::string> EffectFields(Effect e) {
  Stats st{0, 1, 1, 1, 1, 0.01, true};
  std::vector<std::string> out;
  for (const Slot& s : SlotsFor(e, st, AuditOptions{})) out.push_back(s.field);
  // The second forms' fields.
  if (e == Effect::kHysteresis) {
    out.push_back("pi_thresholds");
    out.push_back("pi_weights");
  }
  if (e == Effect::kNonlinearity) {
    out.push_back("power_exponent");
    out.push_back("full_scale");
  }
  return out;
}

absl::StatusOr<AuditReport> RunAudit(const MeasuredData& data, const AuditOptions& o) {
  if (!(o.heldout_fraction >= 0.1 && o.heldout_fraction <= 0.6))
    return absl::InvalidArgumentError(absl::StrCat("heldout_fraction: must be in [0.1, 0.6], got ", o.heldout_fraction));
  if (!(o.min_gain >= 0 && o.min_gain < 1))
    return absl::InvalidArgumentError(absl::StrCat("min_gain: must be in [0, 1), got ", o.min_gain));
  if (o.max_causes < 0 || o.max_causes > kNumEffects)
    return absl::InvalidArgumentError(absl::StrCat("max_causes: must be in [0, 8], got ", o.max_causes));
  if (!(o.max_delay > 0) || !(o.max_lag > 0))
    return absl::InvalidArgumentError("max_delay/max_lag: must be > 0");
  if (o.max_evaluations < 0 || o.max_evaluations > 100000)
    return absl::InvalidArgumentError("max_evaluations: must be in [0, 100000]");
  if (o.min_samples < kMinAuditSamples)
    return absl::InvalidArgumentError(absl::StrCat("min_samples: must be >= ", kMinAuditSamples));
  if (auto st = ValidateMeasuredData(data, o.min_samples); !st.ok()) return st;
  if (o.model) {
    if (auto st = sim::ValidateSensorModel(*o.model); !st.ok()) return st;
  }

  const int n = static_cast<int>(data.t.size());
  const int n_train = static_cast<int>(std::lround(n * (1 - o.heldout_fraction)));
  const int n_h = n - n_train;

  Stats st;
  {
    auto [lo, hi] = std::minmax_element(data.reference.begin(), data.reference.end());
    st.fmin = *lo;
    st.fmax = *hi;
    st.range = st.fmax - st.fmin;
    st.fabsmax = std::max(std::abs(st.fmin), std::abs(st.fmax));
    st.duration = data.t.back() - data.t.front();
    std::vector<double> dts;
    for (int i = 1; i < n; ++i)
      if (data.t[i] > data.t[i - 1]) dts.push_back(data.t[i] - data.t[i - 1]);
    std::nth_element(dts.begin(), dts.begin() + dts.size() / 2, dts.end());
    st.dt = dts.empty() ? 1.0 : dts[dts.size() / 2];
    st.has_shear = !data.shear.empty();
  }

  AuditReport rep;
  rep.source = data.source;
  rep.n_samples = n;
  rep.n_train = n_train;
  rep.n_heldout = n_h;
  rep.skipped_nan_rows = data.skipped_nan_rows;
  rep.split_time = data.t[n_train];
  rep.reading_units = o.reading_units;
  rep.notes = data.notes;

  Engine eng(data, n_train);
  EffectParams base = o.model ? o.model->effects : EffectParams{};
  if (base.curvature == 0) base.full_scale = st.fabsmax > 0 ? st.fabsmax : 1.0;
  if (o.model) {
    const auto pred = sim::PredictReading(*o.model, data.t, data.reference, data.shear, data.segment_starts);
    double r = 0;
    for (int i = n_train; i < n; ++i) r += (data.reading[i] - pred[i]) * (data.reading[i] - pred[i]);
    rep.given_model_heldout_rms = std::sqrt(r / n_h);
  }

  std::vector<Effect> candidates = o.candidates.empty() ? AllEffects() : o.candidates;
  if (!st.has_shear) {
    candidates.erase(std::remove(candidates.begin(), candidates.end(), Effect::kCrosstalk), candidates.end());
    rep.notes.push_back("no 'shear' column: the crosstalk candidate was not tried");
  }

  // Two streams with an estimated clock offset: a constant delay between the
  // streams is not identifiable as a sensor effect, so the 'delay' candidate
  // is replaced by a nuisance delay fitted with every model (the refinement
  // of the clock offset, reported as clock_offset_s).
  const bool offset_nuisance = data.clock_offset_source == MeasuredData::ClockOffset::kEstimated;
  std::vector<Effect> nuisance;
  if (offset_nuisance) {
    if (std::find(candidates.begin(), candidates.end(), Effect::kDelay) != candidates.end())
      rep.notes.push_back(
          "clock offset estimated from the two streams: a constant sensor delay is indistinguishable from a clock "
          "offset, so 'delay' is not a candidate cause; it is part of clock_offset_s (give --clock-offset to fix the "
          "offset and audit the delay)");
    candidates.erase(std::remove(candidates.begin(), candidates.end(), Effect::kDelay), candidates.end());
    if (base.delay != 0)
      rep.notes.push_back("the given model's delay is replaced by the clock-offset refinement");
    base.delay = 0;
    nuisance.push_back(Effect::kDelay);
    base = FitEffect(eng, Effect::kDelay, base, {}, st, o).p;
  }
  std::vector<Effect> selected;
  auto refit_set = [&]() {
    std::vector<Effect> v = nuisance;
    v.insert(v.end(), selected.begin(), selected.end());
    return v;
  };

  // ---- nominal
  Eval ev_cur = eng.Evaluate(base, true);
  int k_cur = 2 + static_cast<int>(nuisance.size());
  double bic_cur = Bic(ev_cur.rss_heldout, n_h, k_cur);
  EffectParams current = base;

  // ---- forward selection
  for (int round = 1; round <= o.max_causes; ++round) {
    if (!selected.empty()) {
      // Converge the named effects first (with the budget a candidate's joint
      // refinement gets), so a new effect is credited only with what it adds.
      bool smooth = true;
      const std::vector<Slot> sel_slots = SelectedSlots(refit_set(), current, st, o, &smooth);
      const int evals = o.max_evaluations * (1 + static_cast<int>(selected.size()));
      FitResult pol = PolishThreshold(eng, Refine(eng, current, sel_slots, smooth, evals, smooth ? 0.1 : 0.02), st);
      if (pol.rss_train < ev_cur.rss_train) {
        current = pol.p;
        ev_cur = eng.Evaluate(current, true);
        bic_cur = Bic(ev_cur.rss_heldout, n_h, k_cur);
      }
    }
    int best = -1;
    double best_bic = std::numeric_limits<double>::infinity();
    Eval best_ev;
    EffectParams best_p;
    std::string best_form;
    std::vector<size_t> round_scores;
    const std::vector<Effect> refit = refit_set();
    for (size_t ci = 0; ci < candidates.size(); ++ci) {
      const Effect e = candidates[ci];
      if (std::find(selected.begin(), selected.end(), e) != selected.end()) continue;
      // Effects with two forms: each form is fitted and scored like a
      // candidate of its own (held-out BIC with its own parameter count).
      std::vector<Form> forms = {DefaultForm(e)};
      if (e == Effect::kHysteresis) forms.push_back(Form::kPrandtlIshlinskii);
      if (e == Effect::kNonlinearity) forms.push_back(Form::kPowerLaw);
      for (Form form : forms) {
        // The other form of the effect is off while this one is fitted (a
        // given model may carry either form).
        EffectParams start = current;
        if (form == Form::kPlay) {
          start.pi_thresholds.clear();
          start.pi_weights.clear();
        } else if (form == Form::kPrandtlIshlinskii) {
          start.hysteresis_width = 0;
        } else if (form == Form::kQuadratic) {
          start.power_exponent = 0;
        } else if (form == Form::kPowerLaw) {
          start.curvature = 0;
        }
        FitResult fr = form == Form::kPrandtlIshlinskii ? FitPrandtlIshlinskii(eng, start, refit, st, o)
                                                        : FitEffect(eng, e, start, refit, st, o, form);
        if (form == Form::kPrandtlIshlinskii && fr.p.pi_thresholds.empty()) continue;  // no hysteresis found
        const Eval ev = eng.Evaluate(fr.p, true);
        const double bic = Bic(ev.rss_heldout, n_h, k_cur + NumParams(e, fr.p));
        CandidateScore cs;
        cs.round = round;
        cs.effect = EffectName(e);
        cs.form = FormName(form);
        cs.parameters = ParamsOf(e, fr.p, st, o);
        cs.array_parameters = ArrayParamsOf(e, fr.p);
        cs.heldout_rms = std::sqrt(ev.rss_heldout / n_h);
        cs.bic = bic;
        round_scores.push_back(rep.candidates.size());
        rep.candidates.push_back(cs);
        if (bic < best_bic) {
          best_bic = bic;
          best = static_cast<int>(ci);
          best_ev = ev;
          best_p = fr.p;
          best_form = FormName(form);
        }
      }
    }
    if (best < 0) break;
    const double rms_before = std::sqrt(ev_cur.rss_heldout / n_h);
    const double rms_after = std::sqrt(best_ev.rss_heldout / n_h);
    const double gain = rms_before > 0 ? 1 - rms_after / rms_before : 0;
    if (!(best_bic < bic_cur && gain >= o.min_gain)) break;
    const Effect e = candidates[best];
    for (size_t idx : round_scores)
      if (rep.candidates[idx].effect == EffectName(e) && rep.candidates[idx].form == best_form)
        rep.candidates[idx].accepted = true;
    Cause c;
    c.effect = EffectName(e);
    c.form = best_form;
    c.parameters = ParamsOf(e, best_p, st, o);
    c.array_parameters = ArrayParamsOf(e, best_p);
    c.heldout_rms_before = rms_before;
    c.heldout_rms_after = rms_after;
    c.gain = 100 * gain;
    c.delta_bic = best_bic - bic_cur;
    rep.causes.push_back(c);
    selected.push_back(e);
    current = best_p;
    ev_cur = best_ev;
    k_cur += NumParams(e, best_p);
    bic_cur = best_bic;
  }
  rep.nominal_adequate = selected.empty();

  // ---- joint refit of all named effects, uncertainties
  bool all_smooth = true;
  const std::vector<Slot> all_slots = SelectedSlots(refit_set(), current, st, o, &all_smooth);
  if (selected.size() + nuisance.size() > 1) {
    FitResult fr = PolishThreshold(eng, Refine(eng, current, all_slots, all_smooth, 2 * o.max_evaluations, 0.01), st);
    double ws = 0;
    for (double w : fr.p.pi_weights) ws += w;
    if (ws > 0)
      for (double& w : fr.p.pi_weights) w /= ws;
    const Eval ev = eng.Evaluate(fr.p, true);
    // Keep the joint refit only when it does not hurt the held-out error.
    if (ev.rss_heldout <= ev_cur.rss_heldout * (1 + 1e-9)) {
      current = fr.p;
      ev_cur = ev;
    }
  }
  for (auto& c : rep.causes) {
    auto e = ParseEffect(c.effect);
    c.parameters = ParamsOf(*e, current, st, o);
    c.array_parameters = ArrayParamsOf(*e, current);
  }
  if (o.uncertainties && !selected.empty()) {
    const double rss0 = eng.Evaluate(current, false).rss_train;
    int k_total = 2 + static_cast<int>(nuisance.size());
    for (Effect e : selected) k_total += NumParams(e, current);
    const double sigma2 = rss0 / std::max(1, n_train - k_total);
    for (auto& c : rep.causes) {
      auto e = ParseEffect(c.effect);
      for (const Slot& s : SlotsFor(*e, st, o, FormOf(*e, current), &current))
        c.uncertainties[s.field] = Uncertainty(eng, current, s, rss0, sigma2);
    }
  }

  // ---- models
  auto make_model = [&](const EffectParams& p, const Eval& ev, const char* what) {
    sim::SensorModel m = o.model ? *o.model : sim::SensorModel{};
    m.units = o.reading_units;
    m.effects = p;
    m.gain = ev.a;
    m.offset = ev.b;
    m.noise = ev.a != 0 ? std::sqrt(ev.rss_train / std::max(1, n_train - k_cur)) / std::abs(ev.a) : 0;
    m.partial_error = 0;
    m.uncertainty.clear();
    m.source = absl::StrCat(what, " of ", data.source);
    return m;
  };
  const Eval ev_nom = eng.Evaluate(base, true);
  rep.nominal_model = make_model(base, ev_nom, "audit nominal fit");
  rep.extended_model = make_model(current, ev_cur, "audit extended model");
  for (const auto& c : rep.causes)
    for (const auto& [k, v] : c.uncertainties) rep.extended_model.uncertainty[k] = v;

  // ---- re-simulate with both models, measure the gain, diagnostics
  rep.t = data.t;
  rep.reference = data.reference;
  rep.reading = data.reading;
  rep.predicted_nominal =
      sim::PredictReading(rep.nominal_model, data.t, data.reference, data.shear, data.segment_starts);
  rep.predicted_extended =
      sim::PredictReading(rep.extended_model, data.t, data.reference, data.shear, data.segment_starts);
  rep.nominal = internal::Diagnose(data, rep.predicted_nominal, rep.nominal_model.gain, n_train, o.max_delay);
  rep.extended = internal::Diagnose(data, rep.predicted_extended, rep.extended_model.gain, n_train, o.max_delay);
  rep.heldout_rms_before = rep.nominal.heldout_rms;
  rep.heldout_rms_after = rep.extended.heldout_rms;
  rep.gain = rep.heldout_rms_before > 0 ? 100 * (1 - rep.heldout_rms_after / rep.heldout_rms_before) : 0;

  // ---- clock offset (two streams)
  if (data.clock_offset_source == MeasuredData::ClockOffset::kFixed) {
    rep.clock_offset_s = data.clock_offset;
    rep.clock_offset_mode = "fixed";
  } else if (offset_nuisance) {
    // The refinement is a delay of the reading behind the aligned reference:
    // reading(t) = F_ref(t - offset - delay).
    rep.clock_offset_mode = "estimated";
    rep.clock_offset_xcorr_s = data.clock_offset;
    rep.clock_offset_refinement_s = current.delay;
    rep.clock_offset_s = data.clock_offset + current.delay;
    rep.clock_offset_correlation = data.clock_offset_correlation;
    // The clock offset is not a property of the sensor: the written models
    // carry no delay (the re-simulated series above include it).
    rep.nominal_model.effects.delay = 0;
    rep.extended_model.effects.delay = 0;
    rep.extended_model.uncertainty.erase("delay");
  }

  if (o.downstream_gain && !selected.empty()) {
    auto dg = internal::MeasureDownstreamGain(rep.nominal_model, rep.extended_model, o.downstream_grasps, o.seed, st.fmax);
    if (dg.ok()) rep.downstream = *dg;
    else rep.notes.push_back(absl::StrCat("downstream gain not measured: ", dg.status().message()));
  }
  return rep;
}

}  // namespace tactforce::audit
