// Fitting effect parameters on the training block (not installed): local
// NLopt refinement over slots, the exact threshold breakpoint scan, one
// effect from a grid start, and the Prandtl-Ishlinskii weights by NNLS.
// Every fit returns the best point it evaluated (never worse than its start).
#pragma once

#include <limits>
#include <vector>

#include "channel_evaluator.h"
#include "effect_space.h"

namespace tactforce::audit::internal {

struct FitResult {
  sim::EffectParams p;
  double rss_train = std::numeric_limits<double>::infinity();  // reading units^2
};

// NLopt local refinement of the slots (normalised to [0, 1]) from `start`:
// LN_BOBYQA when smooth, else LN_SBPLX; at most max_evaluations, initial step
// `step` (normalised).
FitResult Refine(ChannelEvaluator& eng, const sim::EffectParams& start,
                 const std::vector<Slot>& slots, bool smooth, int max_evaluations, double step);

// With a threshold in `in`: scans the exact breakpoints of the RSS near it
// and takes the middle of the best flat interval (returns `in` otherwise).
FitResult PolishThreshold(ChannelEvaluator& eng, const FitResult& in, const RunStats& st);

// Fits effect e (in `form`) on top of `current`: coarse grid over its first
// slot (crossed with the grid of the second), a finer grid around the best
// for non-smooth effects, then a refinement jointly with the effects
// `selected` already in the model, and the threshold polish.
FitResult FitEffect(ChannelEvaluator& eng, Effect e, const sim::EffectParams& current,
                    const std::vector<Effect>& selected, const RunStats& st, const AuditOptions& o,
                    Form form = Form::kOnly);

// Prandtl-Ishlinskii hysteresis on a fixed radius grid (0 and 12 radii
// geometric in [0.002 R, 0.1 R]) on top of `current`: NNLS weights with
// either sign of the gain, zero weights pruned, the rest normalised to sum 1;
// refined jointly with a following static nonlinearity or the effects
// `selected`. Returns `current` when no NNLS solution with hysteresis
// improves on it.
FitResult FitPrandtlIshlinskii(ChannelEvaluator& eng, const sim::EffectParams& current,
                               const std::vector<Effect>& selected, const RunStats& st,
                               const AuditOptions& o);

}  // namespace tactforce::audit::internal
