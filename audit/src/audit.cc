// RunAudit, the audit's driver: validates the options and the data, fits the
// nominal model (with the clock-offset nuisance delay for two streams with an
// estimated offset), selects causes (cause_selection.cc), re-fits them
// jointly with uncertainties (joint_refit.cc), builds the nominal and
// extended sensor models, re-simulates the run with both for the gain and the
// diagnostics (diagnostics.cc), reports the clock offset and measures the
// downstream gain (downstream.cc). The method is in the README and audit.h.
#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "audit_internal.h"
#include "cause_selection.h"
#include "effect_fit.h"
#include "tactforce/audit/audit.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::audit {
namespace {

using internal::AffineFit;
using internal::ChannelEvaluator;
using internal::RunStats;
using internal::Selection;
using sim::EffectParams;

// Checks the options, the data and a given model; InvalidArgument naming the
// option, or the data's file and line.
absl::Status ValidateAuditInputs(const MeasuredData& data, const AuditOptions& o) {
  if (!(o.heldout_fraction >= 0.1 && o.heldout_fraction <= 0.6))
    return absl::InvalidArgumentError(
        absl::StrCat("heldout_fraction: must be in [0.1, 0.6], got ", o.heldout_fraction));
  if (!(o.min_gain >= 0 && o.min_gain < 1))
    return absl::InvalidArgumentError(
        absl::StrCat("min_gain: must be in [0, 1), got ", o.min_gain));
  if (!(o.min_rms_drop >= 0 && o.min_rms_drop < 1))
    return absl::InvalidArgumentError(
        absl::StrCat("min_rms_drop: must be in [0, 1), got ", o.min_rms_drop));
  if (o.max_causes < 0 || o.max_causes > kNumEffects)
    return absl::InvalidArgumentError(
        absl::StrCat("max_causes: must be in [0, 8], got ", o.max_causes));
  if (!(o.max_delay > 0) || !(o.max_lag > 0))
    return absl::InvalidArgumentError("max_delay/max_lag: must be > 0");
  if (o.blocks < 0 || o.blocks > 10)
    return absl::InvalidArgumentError(absl::StrCat("blocks: must be in [0, 10], got ", o.blocks));
  if (!(o.silent_sigmas > 0) || !std::isfinite(o.silent_sigmas))
    return absl::InvalidArgumentError(
        absl::StrCat("silent_sigmas: must be a finite number > 0, got ", o.silent_sigmas));
  if (o.max_evaluations < 0 || o.max_evaluations > 100000)
    return absl::InvalidArgumentError("max_evaluations: must be in [0, 100000]");
  if (o.min_samples < kMinAuditSamples)
    return absl::InvalidArgumentError(absl::StrCat("min_samples: must be >= ", kMinAuditSamples));
  TF_RETURN_IF_ERROR(ValidateMeasuredData(data, o.min_samples));
  if (o.model) {
    TF_RETURN_IF_ERROR(sim::ValidateSensorModel(*o.model));
  }
  return absl::OkStatus();
}

// The report's header: source, sample counts, split time, units, the data's notes.
AuditReport StartReport(const MeasuredData& data, const AuditOptions& o, int n_train) {
  AuditReport rep;
  rep.source = data.source;
  rep.n_samples = static_cast<int>(data.t.size());
  rep.n_train = n_train;
  rep.n_heldout = rep.n_samples - n_train;
  rep.skipped_nan_rows = data.skipped_nan_rows;
  rep.split_time = data.t[n_train];
  rep.reading_units = o.reading_units;
  rep.notes = data.notes;
  return rep;
}

// The effects the nominal fit starts from: the given model's, or none; the
// curvature's full scale is the largest |reference| unless a curvature is set.
EffectParams BaseEffects(const AuditOptions& o, const RunStats& st) {
  EffectParams base = o.model ? o.model->effects : EffectParams{};
  if (base.curvature == 0) base.full_scale = st.fabsmax > 0 ? st.fabsmax : 1.0;
  return base;
}

// Held-out RMS of the given model as given (reading units).
double GivenModelHeldoutRms(const sim::SensorModel& model, const MeasuredData& data, int n_train) {
  const int n = static_cast<int>(data.t.size());
  const auto pred =
      sim::PredictReading(model, data.t, data.reference, data.shear, data.segment_starts);
  double r = 0;
  for (int i = n_train; i < n; ++i) r += (data.reading[i] - pred[i]) * (data.reading[i] - pred[i]);
  return std::sqrt(r / (n - n_train));
}

// The candidate causes: o.candidates (empty = all), without crosstalk when
// the data have no shear column (said in the notes).
std::vector<Effect> ChooseCandidates(const AuditOptions& o, const RunStats& st,
                                     std::vector<std::string>* notes) {
  std::vector<Effect> candidates = o.candidates.empty() ? AllEffects() : o.candidates;
  if (!st.has_shear) {
    candidates.erase(std::remove(candidates.begin(), candidates.end(), Effect::kCrosstalk),
                     candidates.end());
    notes->push_back("no 'shear' column: the crosstalk candidate was not tried");
  }
  return candidates;
}

// Two streams with an estimated clock offset: a constant delay between the
// streams is not identifiable as a sensor effect, so 'delay' leaves the
// candidates and becomes a nuisance delay fitted into base and re-fitted with
// every model (the refinement of the clock offset). Returns the nuisance
// effects (none for one clock).
std::vector<Effect> MakeDelayNuisance(const MeasuredData& data, ChannelEvaluator& eng,
                                      const RunStats& st, const AuditOptions& o,
                                      std::vector<Effect>* candidates, EffectParams* base,
                                      std::vector<std::string>* notes) {
  if (data.clock_offset_source != MeasuredData::ClockOffset::kEstimated) return {};
  if (std::find(candidates->begin(), candidates->end(), Effect::kDelay) != candidates->end())
    notes->push_back(
        "clock offset estimated from the two streams: a constant sensor delay is indistinguishable "
        "from a clock "
        "offset, so 'delay' is not a candidate cause; it is part of clock_offset_s (give "
        "--clock-offset to fix the "
        "offset and audit the delay)");
  candidates->erase(std::remove(candidates->begin(), candidates->end(), Effect::kDelay),
                    candidates->end());
  if (base->delay != 0)
    notes->push_back("the given model's delay is replaced by the clock-offset refinement");
  base->delay = 0;
  *base = internal::FitEffect(eng, Effect::kDelay, *base, {}, st, o).p;
  return {Effect::kDelay};
}

// A sensor model with effects p and fit's gain and offset; noise = the
// training residual's standard deviation (k parameters) in N.
sim::SensorModel MakeModel(const MeasuredData& data, const AuditOptions& o, const EffectParams& p,
                           const AffineFit& fit, int n_train, int k, const char* what) {
  sim::SensorModel m = o.model ? *o.model : sim::SensorModel{};
  m.units = o.reading_units;
  m.effects = p;
  m.gain = fit.a;
  m.offset = fit.b;
  m.noise = fit.a != 0 ? std::sqrt(fit.rss_train / std::max(1, n_train - k)) / std::abs(fit.a) : 0;
  m.partial_error = 0;
  m.uncertainty.clear();
  m.source = absl::StrCat(what, " of ", data.source);
  return m;
}

// The nominal model (base, fitted on the measured reading by `measured`) and
// the extended one (the selection's, fitted on the working reading without
// a named phantom), with the causes' uncertainties.
void BuildModels(const MeasuredData& data, const AuditOptions& o, ChannelEvaluator& measured,
                 ChannelEvaluator& eng, const EffectParams& base, const Selection& s,
                 AuditReport* rep) {
  const AffineFit nominal_fit = measured.Evaluate(base, true);
  rep->nominal_model =
      MakeModel(data, o, base, nominal_fit, eng.n_train(), s.k, "audit nominal fit");
  rep->extended_model =
      MakeModel(data, o, s.params, s.fit, eng.n_train(), s.k, "audit extended model");
  for (const auto& c : rep->causes)
    for (const auto& [k, v] : c.uncertainties) rep->extended_model.uncertainty[k] = v;
}

// Re-simulates the run with both models: the predicted series (the extended
// one with a named phantom added), their diagnostics, held-out RMS
// before/after and the percent gain.
void Resimulate(const MeasuredData& data, const AuditOptions& o, const Selection& s,
                AuditReport* rep) {
  rep->t = data.t;
  rep->reference = data.reference;
  rep->reading = data.reading;
  rep->predicted_nominal = sim::PredictReading(rep->nominal_model, data.t, data.reference,
                                               data.shear, data.segment_starts);
  rep->predicted_extended = sim::PredictReading(rep->extended_model, data.t, data.reference,
                                                data.shear, data.segment_starts);
  if (s.phantom) {
    const auto profile = internal::PhantomProfile(data, s.release_level, s.phantom_decay);
    for (size_t i = 0; i < profile.size(); ++i)
      rep->predicted_extended[i] += rep->extended_model.gain * s.phantom_force * profile[i];
  }
  rep->nominal = internal::Diagnose(data, rep->predicted_nominal, rep->nominal_model.gain,
                                    rep->n_train, o.max_delay);
  rep->extended = internal::Diagnose(data, rep->predicted_extended, rep->extended_model.gain,
                                     rep->n_train, o.max_delay);
  rep->heldout_rms_before = rep->nominal.heldout_rms;
  rep->heldout_rms_after = rep->extended.heldout_rms;
  rep->gain = rep->heldout_rms_before > 0
                  ? 100 * (1 - rep->heldout_rms_after / rep->heldout_rms_before)
                  : 0;
}

// Two streams: the clock offset used. Estimated = cross-correlation + the
// nuisance delay `refinement` (s); the written models then carry no delay.
void ReportClockOffset(const MeasuredData& data, double refinement, AuditReport* rep) {
  if (data.clock_offset_source == MeasuredData::ClockOffset::kFixed) {
    rep->clock_offset_s = data.clock_offset;
    rep->clock_offset_mode = "fixed";
  } else if (data.clock_offset_source == MeasuredData::ClockOffset::kEstimated) {
    // The refinement is a delay of the reading behind the aligned reference:
    // reading(t) = F_ref(t - offset - delay).
    rep->clock_offset_mode = "estimated";
    rep->clock_offset_xcorr_s = data.clock_offset;
    rep->clock_offset_refinement_s = refinement;
    rep->clock_offset_s = data.clock_offset + refinement;
    rep->clock_offset_correlation = data.clock_offset_correlation;
    // The clock offset is not a property of the sensor: the written models
    // carry no delay (the re-simulated series include it).
    rep->nominal_model.effects.delay = 0;
    rep->extended_model.effects.delay = 0;
    rep->extended_model.uncertainty.erase("delay");
  }
}

// The downstream gain of the report's models (a note when it fails).
void AddDownstreamGain(const AuditOptions& o, const RunStats& st, AuditReport* rep) {
  auto dg = internal::MeasureDownstreamGain(rep->nominal_model, rep->extended_model,
                                            o.downstream_grasps, o.seed, st.fmax);
  if (dg.ok())
    rep->downstream = *dg;
  else
    rep->notes.push_back(absl::StrCat("downstream gain not measured: ", dg.status().message()));
}

// The blocked hold-out's block times, and for every channel cause the
// blocks in which it lowers the re-simulated residual.
void ReportBlocks(ChannelEvaluator& all, const AuditOptions& o, const Selection& s,
                  AuditReport* rep) {
  const MeasuredData& d = all.data();
  if (o.blocks < 2) return;
  const std::vector<int> edges = internal::BlockEdges(static_cast<int>(d.t.size()), o.blocks);
  for (size_t b = 0; b + 1 < edges.size(); ++b) rep->block_times.push_back(d.t[edges[b]]);
  rep->block_times.push_back(d.t.back());
  for (Cause& c : rep->causes) {
    auto e = ParseEffect(c.effect);
    if (!e.ok()) continue;
    // A cause of the blocked hold-out keeps the blocks its held-out scores showed.
    const std::vector<int> held_out_blocks = c.blocks;
    internal::BlocksShowing(all, edges, s.params, internal::EffectOff(s.params, *e), o.min_gain,
                            &c);
    if (c.found_by == "blocked") c.blocks = held_out_blocks;
  }
}

}  // namespace

absl::StatusOr<AuditReport> RunAudit(const MeasuredData& data, const AuditOptions& o) {
  TF_RETURN_IF_ERROR(ValidateAuditInputs(data, o));
  const int n = static_cast<int>(data.t.size());
  const int n_train = static_cast<int>(std::lround(n * (1 - o.heldout_fraction)));
  const RunStats st = internal::ComputeRunStats(data);
  AuditReport rep = StartReport(data, o, n_train);
  // The working copy: a named phantom is subtracted from its reading.
  MeasuredData work = data;
  ChannelEvaluator eng(work, n_train);
  ChannelEvaluator all(work, n);  // every sample a training sample
  EffectParams base = BaseEffects(o, st);
  if (o.model) rep.given_model_heldout_rms = GivenModelHeldoutRms(*o.model, data, n_train);
  std::vector<Effect> candidates = ChooseCandidates(o, st, &rep.notes);
  std::vector<Effect> nuisance =
      MakeDelayNuisance(data, eng, st, o, &candidates, &base, &rep.notes);

  auto interrupted = [&o](const char* stage) -> absl::Status {
    if (o.interrupt && o.interrupt())
      return absl::CancelledError(absl::StrCat("interrupted ", stage));
    return absl::OkStatus();
  };
  TF_RETURN_IF_ERROR(interrupted("before the cause selection"));
  Selection s = internal::StartSelection(eng, base, std::move(nuisance));
  s.release_level = st.fmin + 0.05 * st.range;
  internal::SelectCauses(eng, candidates, st, o, &s, &rep, &work);
  internal::SelectCausesBlocked(eng, all, candidates, st, o, &s, &rep);
  TF_RETURN_IF_ERROR(interrupted("during the cause selection"));
  // A cause found by the blocked hold-out may be absent from the training
  // block: the final fits then use every sample.
  const bool blocked = std::any_of(rep.causes.begin(), rep.causes.end(),
                                   [](const Cause& c) { return c.found_by == "blocked"; });
  ChannelEvaluator& final_eng = blocked ? all : eng;
  internal::RefitJointly(final_eng, st, o, &s, &rep.causes);
  TF_RETURN_IF_ERROR(interrupted("after the joint refit"));
  if (o.uncertainties && !s.named.empty())
    internal::EstimateUncertainties(final_eng, st, o, s, &rep.causes);
  TF_RETURN_IF_ERROR(interrupted("after the uncertainties"));
  s.fit = eng.Evaluate(s.params, true);
  ReportBlocks(all, o, s, &rep);
  if (auto pa = internal::FindPartialActivation(data, o))
    rep.causes.insert(rep.causes.begin(), *pa);
  rep.nominal_adequate = rep.causes.empty();

  ChannelEvaluator measured(data, n_train);
  BuildModels(data, o, measured, eng, base, s, &rep);
  Resimulate(data, o, s, &rep);
  ReportClockOffset(data, s.params.delay, &rep);
  if (o.downstream_gain && !s.named.empty()) AddDownstreamGain(o, st, &rep);
  return rep;
}

}  // namespace tactforce::audit
