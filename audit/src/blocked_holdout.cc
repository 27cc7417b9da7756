// The blocked hold-out (k-fold in time). The selection on the final block
// cannot see an effect that appears only late: its training block holds none
// of it. Here the run is cut into `blocks` contiguous blocks of equal sample
// count; fold k holds block k out and trains on the others. Each fold is the
// data reordered (the other blocks in time order, then block k), every block
// a segment of its own, so the unchanged fitting code trains on the first
// n - |block k| samples and scores on the rest; dynamic state restarts at
// each block (a transient of a few time constants) and drift's reference
// time moves (absorbed by the offset). A candidate's score is the held-out
// RSS summed over the folds (every sample held out once), BIC over all n.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>

#include "cause_selection.h"
#include "effect_fit.h"

namespace tactforce::audit::internal {

using sim::EffectParams;

std::vector<int> BlockEdges(int n, int blocks) {
  std::vector<int> edges;
  for (int k = 0; k <= blocks; ++k) edges.push_back(static_cast<int>(std::lround(double(n) * k / blocks)));
  return edges;
}

namespace {

// The blocks `which` (0-based, in time order), each a segment.
MeasuredData BlocksData(const MeasuredData& d, const std::vector<int>& edges, const std::vector<int>& which) {
  MeasuredData f;
  f.source = d.source;
  for (int b : which) {
    f.segment_starts.push_back(static_cast<int>(f.t.size()));
    for (int i = edges[b]; i < edges[b + 1]; ++i) {
      if (i > edges[b] && std::binary_search(d.segment_starts.begin(), d.segment_starts.end(), i))
        f.segment_starts.push_back(static_cast<int>(f.t.size()));
      f.t.push_back(d.t[i]);
      f.reference.push_back(d.reference[i]);
      f.reading.push_back(d.reading[i]);
      if (!d.shear.empty()) f.shear.push_back(d.shear[i]);
      f.trial.push_back(d.trial.empty() ? 0 : d.trial[i]);
    }
  }
  return f;
}

// Fold k's data: blocks other than k in time order, then block k; a segment
// starts at every block and at every trial start inside one.
MeasuredData FoldData(const MeasuredData& d, const std::vector<int>& edges, int k) {
  std::vector<int> order;
  for (int b = 0; b + 1 < static_cast<int>(edges.size()); ++b)
    if (b != k) order.push_back(b);
  order.push_back(k);
  return BlocksData(d, edges, order);
}

// One fold: its data, evaluator and selection state (the named effects
// fitted on the fold's training blocks).
struct Fold {
  MeasuredData data;
  std::unique_ptr<ChannelEvaluator> eng;
  Selection s;
};

// A candidate (effect, form) fitted on every fold.
struct FoldedCandidate {
  int candidate = -1;
  Form form = Form::kOnly;
  double rss = 0;  // held-out RSS summed over the folds
  int k = 0;       // parameters it adds (the largest over the folds)
  std::vector<EffectParams> params;
  std::vector<AffineFit> fits;
  std::vector<int> shown;  // blocks (0-based) whose held-out RMS it lowers by >= min_gain
  bool subset = false;     // scored as present in `shown` only
};

// Scores a folded candidate two ways and keeps the better held-out BIC:
// stationary (in every block: the summed held-out RSS) or present only in
// the blocks it improves by at least min_gain (their held-out RSS with it,
// the others' without it; choosing the blocks counts as one more parameter).
double ScoreFolded(const std::vector<Fold>& folds, int n, int k0, double min_gain, FoldedCandidate* fc) {
  double rss_subset = 0;
  fc->shown.clear();
  for (size_t k = 0; k < folds.size(); ++k) {
    const double r0 = folds[k].s.fit.rss_heldout, r1 = fc->fits[k].rss_heldout;
    const bool shows = r0 > 0 && 1 - std::sqrt(r1 / r0) >= min_gain;
    if (shows) fc->shown.push_back(static_cast<int>(k));
    rss_subset += shows ? r1 : r0;
  }
  const double bic_all = Bic(fc->rss, n, k0 + fc->k);
  const double bic_subset = Bic(rss_subset, n, k0 + fc->k + 1);
  fc->subset = !fc->shown.empty() && fc->shown.size() < folds.size() && bic_subset < bic_all;
  if (fc->subset) fc->rss = rss_subset;
  return fc->subset ? bic_subset : bic_all;
}

FoldedCandidate FitOnFolds(std::vector<Fold>& folds, Effect e, Form form, const RunStats& st,
                           const AuditOptions& o) {
  FoldedCandidate fc;
  fc.form = form;
  for (Fold& f : folds) {
    const EffectParams start = StartForForm(f.s.params, form);
    FitResult fr = form == Form::kPrandtlIshlinskii ? FitPrandtlIshlinskii(*f.eng, start, f.s.Refitted(), st, o)
                                                    : FitEffect(*f.eng, e, start, f.s.Refitted(), st, o, form);
    const AffineFit ev = f.eng->Evaluate(fr.p, true);
    fc.rss += ev.rss_heldout;
    fc.k = std::max(fc.k, NumParams(e, fr.p));
    fc.params.push_back(fr.p);
    fc.fits.push_back(ev);
  }
  return fc;
}

// The best (effect, form) of a blocked round by the summed held-out BIC;
// every one is recorded in rep->candidates (parameters of the last fold).
FoldedCandidate BestOnFolds(std::vector<Fold>& folds, const std::vector<Effect>& candidates, int round,
                            const RunStats& st, const AuditOptions& o, const Selection& s, int n,
                            AuditReport* rep, double* best_bic) {
  FoldedCandidate best;
  *best_bic = std::numeric_limits<double>::infinity();
  for (size_t ci = 0; ci < candidates.size(); ++ci) {
    const Effect e = candidates[ci];
    if (std::find(s.named.begin(), s.named.end(), e) != s.named.end()) continue;
    for (Form form : FormsOf(e)) {
      FoldedCandidate fc = FitOnFolds(folds, e, form, st, o);
      if (fc.k == 0) continue;  // e.g. no PI hysteresis found on any fold
      fc.candidate = static_cast<int>(ci);
      const double bic = ScoreFolded(folds, n, s.k, o.min_gain, &fc);
      CandidateScore cs;
      cs.round = round;
      cs.effect = EffectName(e);
      cs.form = FormName(form);
      cs.parameters = ParamsOf(e, fc.params.back(), st, o);
      cs.parameters["blocked_holdout"] = 1;
      cs.parameters["blocks_showing"] = static_cast<double>(fc.shown.size());
      cs.heldout_rms = std::sqrt(fc.rss / n);
      cs.bic = bic;
      rep->candidates.push_back(cs);
      if (bic < *best_bic) {
        *best_bic = bic;
        best = std::move(fc);
      }
    }
  }
  return best;
}

std::vector<Fold> MakeFolds(const MeasuredData& d, const std::vector<int>& edges, const Selection& s) {
  const int blocks = static_cast<int>(edges.size()) - 1;
  std::vector<Fold> folds(blocks);
  for (int k = 0; k < blocks; ++k) {
    folds[k].data = FoldData(d, edges, k);
    const int n_train = static_cast<int>(d.t.size()) - (edges[k + 1] - edges[k]);
    folds[k].eng = std::make_unique<ChannelEvaluator>(folds[k].data, n_train);
    folds[k].s = s;
    folds[k].s.fit = folds[k].eng->Evaluate(s.params, true);
  }
  return folds;
}

// Re-converges the named effects on every fold's training blocks, so a
// candidate is credited only with what it adds.
void ReconvergeFolds(std::vector<Fold>* folds, const RunStats& st, const AuditOptions& o) {
  for (Fold& f : *folds) {
    if (f.s.named.empty() && f.s.nuisance.empty()) continue;
    ReconvergeNamed(*f.eng, st, o, &f.s);
    f.s.fit = f.eng->Evaluate(f.s.params, true);
  }
}

}  // namespace

EffectParams EffectOff(EffectParams p, Effect e) {
  switch (e) {
    case Effect::kDeadzone: p.threshold = 0, p.threshold_shift = 0; break;
    case Effect::kSaturation: p.saturation = 0; break;
    case Effect::kNonlinearity: p.curvature = 0, p.power_exponent = 0; break;
    case Effect::kHysteresis: p.hysteresis_width = 0, p.pi_thresholds.clear(), p.pi_weights.clear(); break;
    case Effect::kDelay: p.delay = 0; break;
    case Effect::kLag: p.lag = 0; break;
    case Effect::kDrift: p.drift = 0; break;
    case Effect::kCrosstalk: p.crosstalk = 0; break;
  }
  return p;
}

void SelectCausesBlocked(ChannelEvaluator& eng, ChannelEvaluator& all, const std::vector<Effect>& candidates,
                         const RunStats& st, const AuditOptions& o, Selection* s, AuditReport* rep) {
  const MeasuredData& d = all.data();
  const int n = static_cast<int>(d.t.size());
  if (o.blocks < 2) return;
  const std::vector<int> edges = BlockEdges(n, o.blocks);
  std::vector<Fold> folds = MakeFolds(d, edges, *s);
  for (int round = 1; static_cast<int>(rep->causes.size()) < o.max_causes; ++round) {
    if (o.interrupt && o.interrupt()) return;
    ReconvergeFolds(&folds, st, o);
    double rss0 = 0;
    for (const Fold& f : folds) rss0 += f.s.fit.rss_heldout;
    const double bic0 = Bic(rss0, n, s->k);
    double bic = 0;
    const size_t first_scored = rep->candidates.size();
    FoldedCandidate best = BestOnFolds(folds, candidates, round, st, o, *s, n, rep, &bic);
    if (best.candidate < 0) return;
    const double rms0 = std::sqrt(rss0 / n), rms1 = std::sqrt(best.rss / n);
    const double gain = rms0 > 0 ? 1 - rms1 / rms0 : 0;
    const double scale = std::abs(s->fit.a) > 0 ? std::abs(s->fit.a) : 1;
    if (!(bic < bic0 && gain >= o.min_gain && (rms0 - rms1) / scale >= o.min_rms_drop * st.range)) return;
    const Effect e = candidates[best.candidate];
    for (size_t i = first_scored; i < rep->candidates.size(); ++i)
      rep->candidates[i].accepted =
          rep->candidates[i].effect == EffectName(e) && rep->candidates[i].form == FormName(best.form);
    for (size_t k = 0; k < folds.size(); ++k) {
      const bool shows = std::find(best.shown.begin(), best.shown.end(), static_cast<int>(k)) != best.shown.end();
      if (!best.subset || shows) {
        folds[k].s.params = best.params[k];
        folds[k].s.fit = best.fits[k];
      }
      folds[k].s.named.push_back(e);
      folds[k].s.k += best.k;
    }
    // The model's parameters: the effect re-fitted on all samples, or on the
    // blocks that show it when it is present in some only.
    const MeasuredData subset = BlocksData(d, edges, best.subset ? best.shown : std::vector<int>{0});
    ChannelEvaluator on_subset(subset, static_cast<int>(subset.t.size()));
    ChannelEvaluator& fit_eng = best.subset ? on_subset : all;
    const EffectParams start = StartForForm(s->params, best.form);
    FitResult fr = best.form == Form::kPrandtlIshlinskii
                       ? FitPrandtlIshlinskii(fit_eng, start, s->Refitted(), st, o)
                       : FitEffect(fit_eng, e, start, s->Refitted(), st, o, best.form);
    // An effect fitted to its "off" values adds nothing (the folds' gain came
    // from re-fitting the named effects).
    if (EffectOff(fr.p, e) == fr.p) return;
    s->named.push_back(e);
    s->params = fr.p;
    s->k += best.k;
    s->fit = eng.Evaluate(s->params, true);
    s->bic = Bic(s->fit.rss_heldout, eng.n_heldout(), s->k);
    Cause c;
    c.effect = EffectName(e);
    c.form = FormName(best.form);
    c.parameters = ParamsOf(e, s->params, st, o);
    c.array_parameters = ArrayParamsOf(e, s->params);
    c.heldout_rms_before = rms0;
    c.heldout_rms_after = rms1;
    c.gain = 100 * gain;
    c.delta_bic = bic - bic0;
    c.found_by = "blocked";
    for (int b : best.shown) c.blocks.push_back(b + 1);

    rep->causes.push_back(c);
  }
}

void BlocksShowing(ChannelEvaluator& all, const std::vector<int>& edges, const EffectParams& with,
                   const EffectParams& without, double min_gain, Cause* c) {
  const std::vector<double>& y = all.data().reading;
  auto block_rss = [&](const EffectParams& p) {
    const AffineFit fit = all.Evaluate(p, false);
    const std::vector<double>& g = all.FullChannel(p);
    std::vector<double> rss(edges.size() - 1, 0.0);
    for (size_t b = 0; b + 1 < edges.size(); ++b)
      for (int i = edges[b]; i < edges[b + 1]; ++i) {
        const double e = y[i] - fit.a * g[i] - fit.b;
        rss[b] += e * e;
      }
    return rss;
  };
  const std::vector<double> r1 = block_rss(with), r0 = block_rss(without);
  c->blocks.clear();
  c->block_gains.clear();
  for (size_t b = 0; b < r0.size(); ++b) {
    const double g = r0[b] > 0 ? 1 - std::sqrt(r1[b] / r0[b]) : 0;
    c->block_gains.push_back(100 * g);
    if (g >= min_gain) c->blocks.push_back(static_cast<int>(b) + 1);
  }
}

}  // namespace tactforce::audit::internal
