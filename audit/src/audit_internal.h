// Internals shared by the audit's source files (not installed).
#pragma once

#include <vector>

#include "tactforce/audit/audit.h"

namespace tactforce::audit::internal {

// Residual diagnostics of a prediction (reading units) against the data.
Diagnostics Diagnose(const MeasuredData& d, const std::vector<double>& predicted, double gain, int n_train,
                     double max_lag_seconds);

// Upper regularised incomplete gamma Q(a, x); chi-square survival is Q(k/2, x/2).
double GammaQ(double a, double x);

absl::StatusOr<DownstreamGain> MeasureDownstreamGain(const sim::SensorModel& nominal,
                                                     const sim::SensorModel& extended, int grasps,
                                                     uint64_t seed, double max_force);

}  // namespace tactforce::audit::internal
