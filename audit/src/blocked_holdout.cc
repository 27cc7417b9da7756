// The blocked hold-out. The selection on the final block cannot see an effect
// that appears only late (its training block holds none of it), and a
// cross-validation that fits one stationary model on the other blocks mixes
// blocks with and without the effect (in trials, a late change then looks
// like drift). So each of `blocks` contiguous blocks of equal sample count is
// audited on its own, with the same held-out rule inside the block: its first
// 1 - heldout_fraction trains, its rest scores (one selection round on top of
// the causes already named). The channel always runs from the recording's
// start: a block is a range of sample indices, not a segment of its own, so
// hysteresis, lag and delay enter it in the state the recording leads to (a
// restart at the block edge, often mid-press, is a transient the block's fit
// would explain with an extra effect). A cause named there must be confirmed
// with the split reversed (fitted on the block's later part, scored on its
// earlier part, the same BIC test, both gaining at least 2 x min_gain:
// several blocks are searched), or, when the later part holds no trace of
// it (an intermittent effect), explain the forward training part by that
// gain too; in both, the effect must beat the same fit with it switched off
// (the gain of a round also holds the joint re-fit of the effects already
// named). The effect confirmed in the most blocks (ties: the larger mean
// held-out gain) that persists to the end becomes a cause, re-fitted on the
// blocks that show it.
#include <algorithm>
#include <cmath>
#include <map>
#include <optional>
#include <string>

#include "cause_selection.h"
#include "effect_fit.h"

namespace tactforce::audit::internal {

using sim::EffectParams;

std::vector<int> BlockEdges(int n, int blocks) {
  std::vector<int> edges;
  for (int k = 0; k <= blocks; ++k)
    edges.push_back(static_cast<int>(std::lround(double(n) * k / blocks)));
  return edges;
}

EffectParams EffectOff(EffectParams p, Effect e) {
  switch (e) {
    case Effect::kDeadzone:
      p.threshold = 0, p.threshold_shift = 0;
      break;
    case Effect::kSaturation:
      p.saturation = 0;
      break;
    case Effect::kNonlinearity:
      p.curvature = 0, p.power_exponent = 0;
      break;
    case Effect::kHysteresis:
      p.hysteresis_width = 0, p.pi_thresholds.clear(), p.pi_weights.clear();
      break;
    case Effect::kDelay:
      p.delay = 0;
      break;
    case Effect::kLag:
      p.lag = 0;
      break;
    case Effect::kDrift:
      p.drift = 0;
      break;
    case Effect::kCrosstalk:
      p.crosstalk = 0;
      break;
  }
  return p;
}

namespace {

// The form named by FormName (kOnly for "").
Form FormFromName(const std::string& name) {
  for (Form f : {Form::kPlay, Form::kPrandtlIshlinskii, Form::kQuadratic, Form::kPowerLaw})
    if (name == FormName(f)) return f;
  return Form::kOnly;
}

// A selection on `eng` that starts from the global one (its named effects at
// their values, gain/offset re-fitted).
Selection LocalSelection(ChannelEvaluator& eng, const Selection& global) {
  Selection s = global;
  s.phantom = false;
  s.fit = eng.Evaluate(s.params, true);
  s.bic = Bic(s.fit.rss_heldout, eng.n_heldout(), s.k);
  return s;
}

// A block's cause must gain this many times min_gain, forward and reversed:
// `blocks` blocks are searched, so a chance gain is more likely somewhere
// (with 1 x min_gain, null runs get small drifts named in single blocks;
// audit/README.md gives the counts).
constexpr double kBlockGainFactor = 2.0;

// Whether effect e in p lowers the held-out RMS on `eng` by at least
// min_gain, and its BIC (k parameters with it), against p with e off.
bool AddsEnough(ChannelEvaluator& eng, const EffectParams& p, Effect e, int k, double min_gain) {
  const AffineFit with = eng.Evaluate(p, true);
  const EffectParams off_params = EffectOff(p, e);
  const AffineFit off = eng.Evaluate(off_params, true);
  const int n_h = eng.n_heldout();
  const double rms_with = std::sqrt(with.rss_heldout / n_h),
               rms_off = std::sqrt(off.rss_heldout / n_h);
  return rms_off > 0 && 1 - rms_with / rms_off >= min_gain &&
         Bic(with.rss_heldout, n_h, k) < Bic(off.rss_heldout, n_h, k - NumParams(e, p));
}

// What one block showed: the effect named there and confirmed.
struct BlockFinding {
  int block = 0;  // 0-based
  Effect effect = Effect::kDeadzone;
  std::string form;
  double rms_before = 0, rms_after = 0, gain = 0, delta_bic = 0;
};

// How much effect e in p lowers the training RMS on `eng` (relative; gain and
// offset fitted with and without it).
double TrainGain(ChannelEvaluator& eng, const EffectParams& p, Effect e) {
  const double rss_with = eng.Evaluate(p, false).rss_train,
               rss_off = eng.Evaluate(EffectOff(p, e), false).rss_train;
  return rss_off > 0 ? 1 - std::sqrt(rss_with / rss_off) : 0;
}

// The reversed split's verdict on effect e found in a block's forward split.
enum class Reversed { kConfirms, kRefutes, kCannotTell };

// Fits e (in `form`) on the block's later part [cut, last) on top of
// `global` and scores it on the earlier part [first, cut) with the block
// tests (BIC, min_gain, beats the same fit with e off): kConfirms when it
// passes; kCannotTell when the later part holds no trace of e (e lowers its
// training RMS by less than min_gain: an intermittent effect, e.g. no force
// above a saturation level there); else kRefutes.
Reversed CheckReversed(const MeasuredData& d, int first, int cut, int last, Effect e, Form form,
                       const RunStats& st, const AuditOptions& o, double min_gain,
                       const Selection& global) {
  ChannelEvaluator re(d, {{cut, last}}, {{first, cut}});
  Selection rs = LocalSelection(re, global);
  const EffectParams start = StartForForm(rs.params, form);
  FitResult fr = form == Form::kPrandtlIshlinskii
                     ? FitPrandtlIshlinskii(re, start, rs.Refitted(), st, o)
                     : FitEffect(re, e, start, rs.Refitted(), st, o, form);
  const AffineFit ev = re.Evaluate(fr.p, true);
  const int k = rs.k + NumParams(e, fr.p);
  const double rms0 = std::sqrt(rs.fit.rss_heldout / re.n_heldout()),
               rms1 = std::sqrt(ev.rss_heldout / re.n_heldout());
  if (Bic(ev.rss_heldout, re.n_heldout(), k) < rs.bic && rms0 > 0 && 1 - rms1 / rms0 >= min_gain &&
      AddsEnough(re, fr.p, e, k, min_gain))
    return Reversed::kConfirms;
  return TrainGain(re, fr.p, e) >= min_gain ? Reversed::kRefutes : Reversed::kCannotTell;
}

// The block's own audit (one round on top of `global`) and the reversed-split
// confirmation; nullopt when nothing is named or it is not confirmed.
std::optional<BlockFinding> AuditBlock(const MeasuredData& d, int first, int last, int block,
                                       const std::vector<Effect>& candidates, const RunStats& st,
                                       const AuditOptions& o, const Selection& global) {
  const int n = last - first, n_train = static_cast<int>(std::lround(n * (1 - o.heldout_fraction)));
  if (n_train < o.min_samples / 2 || n - n_train < o.min_samples / 2) return std::nullopt;
  ChannelEvaluator fe(d, {{first, first + n_train}}, {{first + n_train, last}});
  Selection fs = LocalSelection(fe, global);
  AuditOptions one = o;
  one.max_causes = 1;
  one.min_gain = kBlockGainFactor * o.min_gain;
  AuditReport scratch;
  SelectCauses(fe, candidates, st, one, &fs, &scratch);
  if (scratch.causes.empty()) return std::nullopt;
  const Cause& c = scratch.causes.front();
  auto e = ParseEffect(c.effect);
  if (!e.ok()) return std::nullopt;
  // Credit the effect only with what it adds: the same fit with it switched
  // off (the named effects as jointly re-fitted with it) must be worse by
  // the gain asked for (else the gain came from re-fitting the named ones).
  if (!AddsEnough(fe, fs.params, *e, fs.k, one.min_gain)) return std::nullopt;
  // Reversed: train on the block's later part, score on its earlier part.
  const Reversed r = CheckReversed(d, first, first + (n - n_train), last, *e, FormFromName(c.form),
                                   st, o, one.min_gain, global);
  // A reversed split that cannot tell leaves the forward split alone: the
  // effect must then explain its own training part too, by the same gain. A
  // fit to noise lowers the training RSS by about (its parameters) / n, far
  // below that (the chance findings of a block pass only on held-out data).
  if (r == Reversed::kRefutes ||
      (r == Reversed::kCannotTell && TrainGain(fe, fs.params, *e) < one.min_gain))
    return std::nullopt;
  return BlockFinding{block,  *e,         c.form, c.heldout_rms_before, c.heldout_rms_after,
                      c.gain, c.delta_bic};
}

// The mean held-out gain of an effect's block findings (percent).
double MeanGain(const std::vector<BlockFinding>& fs) {
  double g = 0;
  for (const auto& f : fs) g += f.gain / fs.size();
  return g;
}

// The effects' findings, most blocks first (ties: the larger mean gain).
std::vector<const std::vector<BlockFinding>*> Ranked(
    const std::map<Effect, std::vector<BlockFinding>>& found) {
  std::vector<const std::vector<BlockFinding>*> ranked;
  for (const auto& [e, fs] : found) ranked.push_back(&fs);
  std::stable_sort(ranked.begin(), ranked.end(), [](const auto* x, const auto* y) {
    return x->size() != y->size() ? x->size() > y->size() : MeanGain(*x) > MeanGain(*y);
  });
  return ranked;
}

// Whether effect e, at its values in p (fitted on earlier samples), persists
// on the samples from `first` to the end (gain/offset fitted there, with and
// without it): they show it (its residual RMS drops by min_gain or more), or
// they cannot show it (it changes their predicted reading by less than
// min_gain x their residual RMS, e.g. no force above a saturation level).
// A chance fit or a transient changes the prediction there and does not help.
bool PersistsLater(const MeasuredData& d, int first, const EffectParams& p, Effect e,
                   double min_gain) {
  const SampleRanges later = {{first, static_cast<int>(d.t.size())}};
  ChannelEvaluator ev(d, later, {});
  const EffectParams off_params = EffectOff(p, e);
  const AffineFit with = ev.Evaluate(p, false), off = ev.Evaluate(off_params, false);
  if (!(off.rss_train > 0)) return false;
  if (1 - std::sqrt(with.rss_train / off.rss_train) >= min_gain) return true;
  const std::vector<double> g_with = ev.TrainChannel(p);
  const std::vector<double>& g_off = ev.TrainChannel(off_params);
  double change = 0;
  for (size_t i = 0; i < g_with.size(); ++i) change += std::pow(off.a * (g_with[i] - g_off[i]), 2);
  return std::sqrt(change / off.rss_train) < min_gain;
}

}  // namespace

void SelectCausesBlocked(ChannelEvaluator& eng, ChannelEvaluator& all,
                         const std::vector<Effect>& candidates, const RunStats& st,
                         const AuditOptions& o, Selection* s, AuditReport* rep) {
  if (o.blocks < 2 || static_cast<int>(rep->causes.size()) >= o.max_causes) return;
  const MeasuredData& d = all.data();
  const std::vector<int> edges = BlockEdges(static_cast<int>(d.t.size()), o.blocks);
  std::map<Effect, std::vector<BlockFinding>> found;
  for (int b = 0; b < o.blocks; ++b) {
    if (o.interrupt && o.interrupt()) return;
    if (auto f = AuditBlock(d, edges[b], edges[b + 1], b, candidates, st, o, *s))
      found[f->effect].push_back(*f);
  }
  const std::vector<BlockFinding>* best = nullptr;
  FitResult fr;
  for (const std::vector<BlockFinding>* fs : Ranked(found)) {
    if (o.interrupt && o.interrupt()) return;
    SampleRanges ranges;
    for (const auto& f : *fs) ranges.emplace_back(edges[f.block], edges[f.block + 1]);
    ChannelEvaluator on_shown(d, ranges, {});
    const Effect e = fs->front().effect;
    const Form form = FormFromName(fs->front().form);
    const EffectParams start = StartForForm(s->params, form);
    fr = form == Form::kPrandtlIshlinskii
             ? FitPrandtlIshlinskii(on_shown, start, s->Refitted(), st, o)
             : FitEffect(on_shown, e, start, s->Refitted(), st, o, form);
    if (EffectOff(fr.p, e) == fr.p) continue;
    // The selection above trained on the run's start: what a block shows
    // and it missed is a change of the sensor, named when it persists to
    // the end (a block's chance fit or a transient does not).
    const int after = fs->back().block + 1;
    if (after == o.blocks || PersistsLater(d, edges[after], fr.p, e, o.min_gain)) {
      best = fs;
      break;
    }
  }
  if (!best) return;
  const Effect e = best->front().effect;
  const int k_added = NumParams(e, fr.p);
  s->named.push_back(e);
  s->params = fr.p;
  s->k += k_added;
  s->fit = eng.Evaluate(s->params, true);
  s->bic = Bic(s->fit.rss_heldout, eng.n_heldout(), s->k);
  Cause c;
  c.effect = EffectName(e);
  c.form = best->front().form;
  c.parameters = ParamsOf(e, s->params, st, o);
  c.array_parameters = ArrayParamsOf(e, s->params);
  // The held-out figures of the blocks that show it (mean over them).
  for (const auto& f : *best) {
    c.heldout_rms_before += f.rms_before / best->size();
    c.heldout_rms_after += f.rms_after / best->size();
    c.delta_bic += f.delta_bic;
    c.blocks.push_back(f.block + 1);
  }
  c.gain = MeanGain(*best);
  c.found_by = "blocked";
  rep->causes.push_back(c);
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
