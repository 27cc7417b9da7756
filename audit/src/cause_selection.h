// The audit's model-building steps after the nominal fit (not installed):
// forward selection of causes (cause_selection.cc), then the joint re-fit of
// the named effects and their uncertainties (joint_refit.cc).
#pragma once

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
  int k = 2;                     // BIC's parameter count: gain, offset, nuisance and named parameters
  double bic = 0;                // held-out BIC of the current model
  // nuisance, then named: the effects re-fitted jointly with each new one.
  std::vector<Effect> Refitted() const;
};

// The selection before any cause: the nominal model `base` (its nuisance
// effects already fitted into it), scored on the held-out block.
Selection StartSelection(ChannelEvaluator& eng, const sim::EffectParams& base, std::vector<Effect> nuisance);

// Forward selection (README, Method 4): each round re-converges the named
// effects, fits every form of every remaining candidate on top of the model
// and scores it by held-out BIC (all recorded in rep->candidates); the best
// becomes a cause in rep->causes when it lowers the BIC and improves the
// held-out RMS by at least min_gain. At most o.max_causes rounds.
void SelectCauses(ChannelEvaluator& eng, const std::vector<Effect>& candidates, const RunStats& st,
                  const AuditOptions& o, Selection* s, AuditReport* rep);

// Re-fits the named and nuisance effects jointly (when there are two or
// more), keeps the result unless the held-out RSS grows, and writes the
// final parameters into the causes.
void RefitJointly(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o, Selection* s,
                  std::vector<Cause>* causes);

// 1-sigma uncertainty of every named parameter: the conditional
// Delta-RSS = sigma^2 interval, sigma^2 = training RSS / (n_train - k).
void EstimateUncertainties(ChannelEvaluator& eng, const RunStats& st, const AuditOptions& o, const Selection& s,
                           std::vector<Cause>* causes);

}  // namespace tactforce::audit::internal
