// The extended model's final fit: all named effects (and the clock-offset
// nuisance delay) refined jointly from the selection's end point, kept only
// when the held-out error does not grow, then 1-sigma uncertainties of every
// named parameter from the conditional Delta-RSS = sigma^2 interval (found by
// bracketing outwards from the estimate and bisecting; autocorrelated
// residuals make these optimistic).
#include <cmath>
#include <limits>

#include "cause_selection.h"
#include "effect_fit.h"

namespace tactforce::audit::internal {

using sim::EffectParams;

void RefitJointly(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o, Selection* s,
                  std::vector<Cause>* causes) {
  bool all_smooth = true;
  const std::vector<Slot> all_slots = SelectedSlots(s->Refitted(), s->params, st, o, &all_smooth);
  if (s->named.size() + s->nuisance.size() > 1) {
    FitResult fr = PolishThreshold(
        eng, Refine(eng, s->params, all_slots, all_smooth, 2 * o.max_evaluations, 0.01), st);
    NormaliseWeights(&fr.p.pi_weights);
    const AffineFit ev = eng.Evaluate(fr.p, true);
    // Keep the joint refit only when it does not hurt the held-out error.
    if (ev.rss_heldout <= s->fit.rss_heldout * (1 + 1e-9)) {
      s->params = fr.p;
      s->fit = ev;
    }
  }
  for (auto& c : *causes) {
    auto e = ParseEffect(c.effect);
    if (!e.ok()) continue;  // phantom, partial_activation: not channel effects
    c.parameters = ParamsOf(*e, s->params, st, o);
    c.array_parameters = ArrayParamsOf(*e, s->params);
  }
}

namespace {

// Distance from p's value of slot s, in direction sign (+1 or -1), at which
// the training RSS first rises by sigma2 over rss0; NaN when it does not
// within the bounds.
double DeltaRssDistance(ChannelEvaluator& eng, const EffectParams& p, const Slot& s, double rss0,
                        double sigma2, double sign) {
  const double x0 = Get(p, s);
  const double limit = sign > 0 ? s.hi - x0 : x0 - s.lo;
  double lo = 0, hi = std::min(limit, 1e-4 * (s.hi - s.lo));
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
  if (!ok) return std::numeric_limits<double>::quiet_NaN();
  for (int it = 0; it < 14; ++it) {
    const double mid = 0.5 * (lo + hi);
    EffectParams q = p;
    Set(q, s, x0 + sign * mid);
    if (eng.Evaluate(q, false).rss_train - rss0 >= sigma2)
      hi = mid;
    else
      lo = mid;
  }
  return 0.5 * (lo + hi);
}

// 1-sigma of slot s: the mean of the two sides' Delta-RSS distances, the one
// found, or the slot's whole width when neither is within bounds.
double Uncertainty(ChannelEvaluator& eng, const EffectParams& p, const Slot& s, double rss0,
                   double sigma2) {
  const double up = DeltaRssDistance(eng, p, s, rss0, sigma2, 1);
  const double down = DeltaRssDistance(eng, p, s, rss0, sigma2, -1);
  const int found = !std::isnan(up) + !std::isnan(down);
  if (found == 2) return 0.5 * (up + down);
  if (found == 1) return std::isnan(up) ? down : up;
  return s.hi - s.lo;  // not constrained within bounds
}

}  // namespace

void EstimateUncertainties(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o,
                           const Selection& s, std::vector<Cause>* causes) {
  const double rss0 = eng.Evaluate(s.params, false).rss_train;
  int k_total = 2 + static_cast<int>(s.nuisance.size());
  for (Effect e : s.named) k_total += NumParams(e, s.params);
  const double sigma2 = rss0 / std::max(1, eng.n_train() - k_total);
  for (auto& c : *causes) {
    auto e = ParseEffect(c.effect);
    if (!e.ok()) continue;
    for (const Slot& sl : SlotsFor(*e, st, o, FormOf(*e, s.params), &s.params))
      c.uncertainties[sl.field] = Uncertainty(eng, s.params, sl, rss0, sigma2);
  }
}

}  // namespace tactforce::audit::internal
