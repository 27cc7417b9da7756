// Fitting one effect's parameters on the training block: a coarse grid start
// (crossed with a second slot's grid, refined around the best for non-smooth
// effects), an NLopt local refinement jointly with the effects already named
// (derivative-free: LN_SBPLX for the non-smooth effects, LN_BOBYQA for the
// smooth ones; every point evaluated is tracked, so roundoff or a forced stop
// keeps the best seen), and for a threshold the exact scan of the RSS
// breakpoints, which the continuous optimisers cannot resolve.
#include "effect_fit.h"

#include <algorithm>
#include <cmath>
#include <nlopt.hpp>
#include <utility>

namespace tactforce::audit::internal {

using sim::EffectParams;

namespace {

struct RefineContext {
  ChannelEvaluator* eng;
  const std::vector<Slot>* slots;
  EffectParams base;
  FitResult* best;
};

// The parameters at the normalised point x (clamped to [0, 1]).
EffectParams ParamsAt(const RefineContext& c, const std::vector<double>& x) {
  EffectParams p = c.base;
  for (size_t i = 0; i < c.slots->size(); ++i) {
    const Slot& s = (*c.slots)[i];
    Set(p, s, s.lo + std::clamp(x[i], 0.0, 1.0) * (s.hi - s.lo));
  }
  return p;
}

double RefineObjective(const std::vector<double>& x, std::vector<double>& grad, void* data) {
  auto* c = static_cast<RefineContext*>(data);
  const EffectParams p = ParamsAt(*c, x);
  const double rss = c->eng->Evaluate(p, false).rss_train;
  if (rss < c->best->rss_train) {
    c->best->rss_train = rss;
    c->best->p = p;
  }
  return rss;
}

}  // namespace

FitResult Refine(ChannelEvaluator& eng, const EffectParams& start, const std::vector<Slot>& slots,
                 bool smooth, int max_evaluations, double step) {
  FitResult best;
  best.p = start;
  best.rss_train = eng.Evaluate(start, false).rss_train;
  if (slots.empty() || max_evaluations <= 0) return best;
  const int k = static_cast<int>(slots.size());
  RefineContext ctx{&eng, &slots, start, &best};
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
    opt.set_min_objective(RefineObjective, &ctx);
    opt.set_maxeval(max_evaluations);
    opt.set_xtol_abs(1e-5);
    opt.set_ftol_rel(1e-9);
    std::vector<double> dxa(k);
    for (int i = 0; i < k; ++i) dxa[i] = std::abs(dx[i]);
    opt.set_initial_step(dxa);
    double f = 0;
    opt.optimize(x, f);
  } catch (const std::exception&) {
    // roundoff / forced stop: keep the best point seen (tracked in the objective)
  }
  return best;
}

namespace {

// The distinct pre-threshold channel values within 5 % of the range of the
// threshold in p, sorted.
std::vector<double> BreakpointsNear(ChannelEvaluator& eng, const EffectParams& p,
                                    const RunStats& st) {
  EffectParams pre = p;
  pre.threshold = 0;
  pre.saturation = 0;
  pre.drift = 0;
  std::vector<double> u = eng.TrainChannel(pre);
  const double th = p.threshold, w = 0.05 * st.range;
  std::vector<double> near;
  for (double v : u)
    if (std::abs(v - th) <= w) near.push_back(v);
  std::sort(near.begin(), near.end());
  near.erase(std::unique(near.begin(), near.end()), near.end());
  return near;
}

// Of the runs of consecutive (threshold, rss) scores within tol of min_rss,
// the one closest to th (its own plateau when th lies in one): [first, last],
// or first = -1 when there is none.
std::pair<long, long> ClosestMinimumRun(const std::vector<std::pair<double, double>>& scores,
                                        double min_rss, double tol, double th) {
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
  return {best_first, best_last};
}

}  // namespace

// The RSS is piecewise constant in the threshold (it only changes when the
// threshold passes a pre-threshold value u_i), and with an activation jump a
// threshold a little off misclassifies crossing samples by ~threshold. Scan
// the exact breakpoints near the estimate and take the middle of the best
// flat interval.
FitResult PolishThreshold(ChannelEvaluator& eng, const FitResult& in, const RunStats& st) {
  if (!(in.p.threshold > 0)) return in;
  const std::vector<double> near = BreakpointsNear(eng, in.p, st);
  if (near.size() < 2) return in;
  // At most ~120 breakpoints, centred on the estimate.
  const double th = in.p.threshold;
  auto it = std::lower_bound(near.begin(), near.end(), th);
  const long c = it - near.begin();
  const long lo = std::max(0L, c - 60), hi = std::min<long>(near.size() - 1, c + 60);
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
  const auto [first, last] = ClosestMinimumRun(scores, min_rss, tol, th);
  if (first < 0) return in;
  FitResult best = in;
  best.p.threshold = 0.5 * (scores[first].first + scores[last].first);
  best.rss_train = eng.Evaluate(best.p, false).rss_train;
  if (best.rss_train > min_rss + tol) {  // numerical corner: take a scanned minimum
    best.p.threshold = scores[first].first;
    best.rss_train = scores[first].second;
  }
  return best.rss_train <= in.rss_train + tol ? best : in;
}

namespace {

// Grid start of an effect with the given slots on top of `current`: every
// value of the first slot's grid (crossed with the second slot's grid), then
// for a non-smooth effect 12 values between the neighbours of the best.
FitResult GridStart(ChannelEvaluator& eng, Effect e, const EffectParams& current,
                    const std::vector<Slot>& slots) {
  FitResult best;
  best.p = current;
  // Evaluates p; true when it is the best so far.
  auto consider = [&](const EffectParams& p) {
    const double rss = eng.Evaluate(p, false).rss_train;
    if (!(rss < best.rss_train)) return false;
    best.rss_train = rss;
    best.p = p;
    return true;
  };
  const Slot& s0 = slots[0];
  int best_i = 0;
  for (size_t i = 0; i < s0.grid.size(); ++i) {
    EffectParams p = current;
    Set(p, s0, s0.grid[i]);
    if (slots.size() == 1) {
      if (consider(p)) best_i = static_cast<int>(i);
      continue;
    }
    for (double v : slots[1].grid) {
      EffectParams q = p;
      Set(q, slots[1], v);
      if (consider(q)) best_i = static_cast<int>(i);
    }
  }
  if (!IsSmooth(e) && s0.grid.size() > 2) {
    const double a = s0.grid[std::max(0, best_i - 1)];
    const double b = s0.grid[std::min<int>(s0.grid.size() - 1, best_i + 1)];
    const EffectParams base = best.p;
    for (double v : LinearGrid(a, b, 12)) {
      EffectParams p = base;
      Set(p, s0, v);
      consider(p);
    }
  }
  return best;
}

}  // namespace

FitResult FitEffect(ChannelEvaluator& eng, Effect e, const EffectParams& current,
                    const std::vector<Effect>& selected, const RunStats& st, const AuditOptions& o,
                    Form form) {
  const std::vector<Slot> slots = SlotsFor(e, st, o, form);
  const FitResult best = GridStart(eng, e, current, slots);
  // Refine the new effect jointly with the effects named before it (an
  // earlier effect may have absorbed part of this one, e.g. delay + lag).
  std::vector<Slot> joint = slots;
  bool smooth = IsSmooth(e);
  for (Slot& sl : SelectedSlots(selected, best.p, st, o, &smooth)) joint.push_back(std::move(sl));
  const int evals = o.max_evaluations * (1 + static_cast<int>(selected.size()));
  FitResult r = Refine(eng, best.p, joint, smooth, evals, smooth ? 0.1 : 0.02);
  return PolishThreshold(eng, r.rss_train <= best.rss_train ? r : best, st);
}

}  // namespace tactforce::audit::internal
