// The audit's model-building steps after the nominal fit (not installed):
// forward selection of causes (cause_selection.cc), then the joint re-fit of
// the named effects and their uncertainties (joint_refit.cc).
#pragma once

#include <optional>
#include <vector>

#include "channel_evaluator.h"
#include "effect_space.h"

namespace tactforce::audit::internal {

// The model while causes are selected: the nominal base plus the effects
// named so far.
struct Selection {
  std::vector<Effect> nuisance;  // re-fitted with every model, never named (the clock-offset delay)
  std::vector<Effect> named;     // causes, in the order named
  sim::EffectParams params;      // the current model's effects
  AffineFit fit;                 // of params, with the held-out RSS
  int k = 2;       // BIC's parameter count: gain, offset, nuisance and named parameters
  double bic = 0;  // held-out BIC of the current model
  // A named phantom (subtracted from the audit's working copy of the
  // reading, so the channel effects are fitted without it).
  bool phantom = false;
  double phantom_force = 0;  // N
  double phantom_decay = 0;  // s
  double release_level = 0;  // N, reference at or below which the sensor is unloaded
  // nuisance, then named: the effects re-fitted jointly with each new one.
  std::vector<Effect> Refitted() const;
};

// The selection before any cause: the nominal model `base` (its nuisance
// effects already fitted into it), scored on the held-out block.
Selection StartSelection(ChannelEvaluator& eng, const sim::EffectParams& base,
                         std::vector<Effect> nuisance);

// Forward selection (README, Method 4): each round re-converges the named
// effects, fits every form of every remaining candidate on top of the model
// and scores it by held-out BIC (all recorded in rep->candidates); the best
// becomes a cause in rep->causes when it lowers the BIC and improves the
// held-out RMS by at least min_gain. At most o.max_causes rounds.
// `work` is the evaluator's data (a working copy): a named phantom is
// subtracted from its reading. Null: no phantom candidate.
void SelectCauses(ChannelEvaluator& eng, const std::vector<Effect>& candidates, const RunStats& st,
                  const AuditOptions& o, Selection* s, AuditReport* rep,
                  MeasuredData* work = nullptr);

// Re-converges the named effects with the budget a candidate's joint
// refinement gets; keeps the result when it lowers the training RSS.
void ReconvergeNamed(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o,
                     Selection* s);

// The effect e switched off in p (its fields at their "off" values).
sim::EffectParams EffectOff(sim::EffectParams p, Effect e);

// The forms a candidate is fitted in, and the start of a fit of `form` (the
// current effects with the effect's other form off).
std::vector<Form> FormsOf(Effect e);
sim::EffectParams StartForForm(const sim::EffectParams& current, Form form);

// ---- phantom (phantom.cc) ----
// The phantom profile exp(-(t - t_r)/decay) at every sample whose reference
// is <= release_level after a loaded sample of the same segment (t_r: the
// first such sample), 0 elsewhere.
std::vector<double> PhantomProfile(const MeasuredData& d, double release_level, double decay);
struct PhantomFit {
  bool ok = false;
  double force = 0, decay = 0;  // N, s
  double coefficient = 0;       // reading units (gain x force)
  double rss_heldout = 0;       // of the current model plus the phantom
  double bic = 0;
};
// Fits the phantom on top of the current model on the training block (decay
// on a log grid 0.02-30 s refined by golden section; coefficient, gain and
// offset by least squares; force > 0) and scores it on the held-out block.
PhantomFit FitPhantom(ChannelEvaluator& eng, const Selection& s);

// ---- blocked hold-out (blocked_holdout.cc) ----
// The sample index where each of `blocks` equal contiguous blocks starts,
// plus n.
std::vector<int> BlockEdges(int n, int blocks);
// The blocked hold-out (README, Method 4b): each of o.blocks contiguous
// blocks audited on its own (one round on top of *s, the split at
// heldout_fraction inside the block) and a cause named there confirmed with
// the split reversed; the effect confirmed in the most blocks becomes a
// cause (found_by "blocked", its blocks listed), re-fitted on those blocks.
// `all` holds every sample as training; `eng` re-scores the selection.
void SelectCausesBlocked(ChannelEvaluator& eng, ChannelEvaluator& all,
                         const std::vector<Effect>& candidates, const RunStats& st,
                         const AuditOptions& o, Selection* s, AuditReport* rep);
// Per block, the relative drop of the residual RMS of `with` versus
// `without` (both re-simulated, gain/offset fitted on all samples):
// fills c->blocks (drop >= min_gain) and c->block_gains (percent).
void BlocksShowing(ChannelEvaluator& all, const std::vector<int>& edges,
                   const sim::EffectParams& with, const sim::EffectParams& without, double min_gain,
                   Cause* c);

// ---- partial activation (taxel_activation.cc) ----
// The cause partial_activation from per-taxel data (README): nullopt when
// every taxel activates or there are no taxel columns.
std::optional<Cause> FindPartialActivation(const MeasuredData& d, const AuditOptions& o);

// Re-fits the named and nuisance effects jointly (when there are two or
// more), keeps the result unless the held-out RSS grows, and writes the
// final parameters into the causes.
void RefitJointly(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o, Selection* s,
                  std::vector<Cause>* causes);

// 1-sigma uncertainty of every named parameter: the conditional
// Delta-RSS = sigma^2 interval, sigma^2 = training RSS / (n_train - k).
void EstimateUncertainties(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o,
                           const Selection& s, std::vector<Cause>* causes);

}  // namespace tactforce::audit::internal
