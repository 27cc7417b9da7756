// Internals shared by the audit's source files (not installed): residual
// diagnostics, the chi-square tail they use, the downstream gain and the
// median time step.
#pragma once

#include <cstdint>
#include <vector>

#include "tactforce/audit/audit.h"

namespace tactforce::audit::internal {

// Residual diagnostics of a prediction (reading units) against the data; the
// first n_train samples are the training block (diagnostics.cc).
Diagnostics Diagnose(const MeasuredData& d, const std::vector<double>& predicted, double gain,
                     int n_train, double max_lag_seconds);

// Upper regularised incomplete gamma Q(a, x); chi-square survival is Q(k/2, x/2).
double GammaQ(double a, double x);

absl::StatusOr<DownstreamGain> MeasureDownstreamGain(const sim::SensorModel& nominal,
                                                     const sim::SensorModel& extended, int grasps,
                                                     uint64_t seed, double max_force);

// Median of the positive time steps t[i] - t[i-1] (s); steps where the time
// restarts (a new trial) or repeats are left out. `fallback` when there is
// no positive step (measured_data.cc).
double MedianStep(const std::vector<double>& t, double fallback);

}  // namespace tactforce::audit::internal
