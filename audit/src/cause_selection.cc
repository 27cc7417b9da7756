// Forward selection of causes. Each round fits every remaining candidate
// (each form of the two-form effects as a candidate of its own) on top of the
// current model, jointly re-refining the effects already named, on the
// training block, and scores it on the held-out block with
// BIC_h = n_h ln(RSS_h / n_h) + k ln(n_h). The best is accepted when BIC_h
// falls, the held-out RMS improves by at least min_gain and falls by at
// least min_rms_drop of the reference force range (force equivalent);
// otherwise selection stops. Before each round the named effects are re-converged, so a
// new effect is credited only with what it adds.
#include "cause_selection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

#include "effect_fit.h"

namespace tactforce::audit::internal {

using sim::EffectParams;

std::vector<Effect> Selection::Refitted() const {
  std::vector<Effect> v = nuisance;
  v.insert(v.end(), named.begin(), named.end());
  return v;
}

Selection StartSelection(ChannelEvaluator& eng, const EffectParams& base,
                         std::vector<Effect> nuisance) {
  Selection s;
  s.fit = eng.Evaluate(base, true);
  s.k = 2 + static_cast<int>(nuisance.size());
  s.bic = Bic(s.fit.rss_heldout, eng.n_heldout(), s.k);
  s.params = base;
  s.nuisance = std::move(nuisance);
  return s;
}

// Re-converges the named effects with the budget a candidate's joint
// refinement gets; keeps the result when it lowers the training RSS.
void ReconvergeNamed(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o,
                     Selection* s) {
  bool smooth = true;
  const std::vector<Slot> slots = SelectedSlots(s->Refitted(), s->params, st, o, &smooth);
  const int evals = o.max_evaluations * (1 + static_cast<int>(s->named.size()));
  FitResult pol =
      PolishThreshold(eng, Refine(eng, s->params, slots, smooth, evals, smooth ? 0.1 : 0.02), st);
  if (pol.rss_train < s->fit.rss_train) {
    s->params = pol.p;
    s->fit = eng.Evaluate(s->params, true);
    s->bic = Bic(s->fit.rss_heldout, eng.n_heldout(), s->k);
  }
}

namespace {}  // namespace

// The forms a candidate is fitted in: the default, plus the second form of
// hysteresis (Prandtl-Ishlinskii) and nonlinearity (power law).
std::vector<Form> FormsOf(Effect e) {
  std::vector<Form> forms = {DefaultForm(e)};
  if (e == Effect::kHysteresis) forms.push_back(Form::kPrandtlIshlinskii);
  if (e == Effect::kNonlinearity) forms.push_back(Form::kPowerLaw);
  return forms;
}

// The start of a fit of `form`: the current effects with the effect's other
// form off (a given model may carry either form).
EffectParams StartForForm(const EffectParams& current, Form form) {
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
  return start;
}

namespace {

// The best candidate of a round.
struct RoundBest {
  int candidate = -1;  // index into the candidates; -1: none was scored
  double bic = std::numeric_limits<double>::infinity();
  AffineFit fit;
  EffectParams params;
  std::string form;
  std::vector<size_t> scored;  // this round's entries in AuditReport::candidates
};

// Fits and scores every form of every candidate not yet named (each recorded
// in rep->candidates) and returns the one with the lowest held-out BIC.
RoundBest ScoreRound(ChannelEvaluator& eng, const std::vector<Effect>& candidates, int round,
                     const RunStats& st, const AuditOptions& o, const Selection& s,
                     AuditReport* rep) {
  RoundBest best;
  const std::vector<Effect> refit = s.Refitted();
  const int n_h = eng.n_heldout();
  for (size_t ci = 0; ci < candidates.size(); ++ci) {
    const Effect e = candidates[ci];
    if (std::find(s.named.begin(), s.named.end(), e) != s.named.end()) continue;
    for (Form form : FormsOf(e)) {
      const EffectParams start = StartForForm(s.params, form);
      FitResult fr = form == Form::kPrandtlIshlinskii
                         ? FitPrandtlIshlinskii(eng, start, refit, st, o)
                         : FitEffect(eng, e, start, refit, st, o, form);
      if (form == Form::kPrandtlIshlinskii && fr.p.pi_thresholds.empty())
        continue;  // no hysteresis found
      const AffineFit ev = eng.Evaluate(fr.p, true);
      const double bic = Bic(ev.rss_heldout, n_h, s.k + NumParams(e, fr.p));
      CandidateScore cs;
      cs.round = round;
      cs.effect = EffectName(e);
      cs.form = FormName(form);
      cs.parameters = ParamsOf(e, fr.p, st, o);
      cs.array_parameters = ArrayParamsOf(e, fr.p);
      cs.heldout_rms = std::sqrt(ev.rss_heldout / n_h);
      cs.bic = bic;
      best.scored.push_back(rep->candidates.size());
      rep->candidates.push_back(cs);
      if (bic < best.bic) {
        best.bic = bic;
        best.candidate = static_cast<int>(ci);
        best.fit = ev;
        best.params = fr.p;
        best.form = FormName(form);
      }
    }
  }
  return best;
}

// Names the round's best a cause when it lowers the held-out BIC, gains at
// least min_gain and lowers the held-out RMS by at least min_rms_drop x the
// reference force range; false (nothing changed) otherwise.
bool AcceptBest(const RoundBest& best, const std::vector<Effect>& candidates, int n_h,
                const RunStats& st, const AuditOptions& o, Selection* s, AuditReport* rep) {
  const double rms_before = std::sqrt(s->fit.rss_heldout / n_h);
  const double rms_after = std::sqrt(best.fit.rss_heldout / n_h);
  const double gain = rms_before > 0 ? 1 - rms_after / rms_before : 0;
  // The absolute floor, in force-equivalent N (RMS / |gain|): a relative gain
  // on a residual already at round-off or CSV-precision size names no cause.
  const double scale = std::abs(s->fit.a) > 0 ? std::abs(s->fit.a) : 1;
  const bool material = (rms_before - rms_after) / scale >= o.min_rms_drop * st.range;
  if (!(best.bic < s->bic && gain >= o.min_gain && material)) return false;
  const Effect e = candidates[best.candidate];
  for (size_t idx : best.scored)
    if (rep->candidates[idx].effect == EffectName(e) && rep->candidates[idx].form == best.form)
      rep->candidates[idx].accepted = true;
  Cause c;
  c.effect = EffectName(e);
  c.form = best.form;
  c.parameters = ParamsOf(e, best.params, st, o);
  c.array_parameters = ArrayParamsOf(e, best.params);
  c.heldout_rms_before = rms_before;
  c.heldout_rms_after = rms_after;
  c.gain = 100 * gain;
  c.delta_bic = best.bic - s->bic;
  rep->causes.push_back(c);
  s->named.push_back(e);
  s->params = best.params;
  s->fit = best.fit;
  s->k += NumParams(e, best.params);
  s->bic = best.bic;
  return true;
}

// Records the phantom candidate of a round; when it beats the round's best
// channel candidate and passes AcceptBest's tests, names it: the phantom is
// subtracted from the working reading and the model re-scored. Returns
// whether it was named.
bool ConsiderPhantom(ChannelEvaluator& eng, const PhantomFit& ph, const RoundBest& best, int round,
                     const RunStats& st, const AuditOptions& o, Selection* s, AuditReport* rep,
                     MeasuredData* work) {
  CandidateScore cs;
  cs.round = round;
  cs.effect = kPhantom;
  cs.parameters = {{"phantom_force", ph.force}, {"phantom_decay", ph.decay}};
  const int n_h = eng.n_heldout();
  cs.heldout_rms = std::sqrt(ph.rss_heldout / n_h);
  cs.bic = ph.bic;
  rep->candidates.push_back(cs);
  if (!(ph.bic < best.bic)) return false;
  const double rms_before = std::sqrt(s->fit.rss_heldout / n_h);
  const double gain = rms_before > 0 ? 1 - cs.heldout_rms / rms_before : 0;
  const double scale = std::abs(s->fit.a) > 0 ? std::abs(s->fit.a) : 1;
  const bool material = (rms_before - cs.heldout_rms) / scale >= o.min_rms_drop * st.range;
  if (!(ph.bic < s->bic && gain >= o.min_gain && material)) return false;
  rep->candidates.back().accepted = true;
  const std::vector<double> profile = PhantomProfile(*work, s->release_level, ph.decay);
  for (size_t i = 0; i < profile.size(); ++i) work->reading[i] -= ph.coefficient * profile[i];
  Cause c;
  c.effect = kPhantom;
  c.parameters = cs.parameters;
  c.parameters["release_level"] = s->release_level;
  c.heldout_rms_before = rms_before;
  c.heldout_rms_after = cs.heldout_rms;
  c.gain = 100 * gain;
  c.delta_bic = ph.bic - s->bic;
  rep->causes.push_back(c);
  s->phantom = true;
  s->phantom_force = ph.force;
  s->phantom_decay = ph.decay;
  s->k += 2;
  s->fit = eng.Evaluate(s->params, true);
  s->bic = Bic(s->fit.rss_heldout, n_h, s->k);
  return true;
}

}  // namespace

void SelectCauses(ChannelEvaluator& eng, const std::vector<Effect>& candidates, const RunStats& st,
                  const AuditOptions& o, Selection* s, AuditReport* rep, MeasuredData* work) {
  for (int round = 1; static_cast<int>(rep->causes.size()) < o.max_causes; ++round) {
    if (o.interrupt && o.interrupt()) return;  // RunAudit reports it
    if (!s->named.empty()) ReconvergeNamed(eng, st, o, s);
    const RoundBest best = ScoreRound(eng, candidates, round, st, o, *s, rep);
    if (work && o.phantom && !s->phantom) {
      const PhantomFit ph = FitPhantom(eng, *s);
      if (ph.ok && ConsiderPhantom(eng, ph, best, round, st, o, s, rep, work)) continue;
    }
    if (best.candidate < 0) break;
    if (!AcceptBest(best, candidates, eng.n_heldout(), st, o, s, rep)) break;
  }
}

}  // namespace tactforce::audit::internal
