// A streaming (sample-by-sample) evaluation of tactforce's tactile sensor
// model (tactforce/sim/sensor_model.h) for closed-loop use: the same effect
// chain, in the same order, with the same parameters as sim::ApplyChannel
// (which needs the whole signal up front), plus noise, gain and offset:
//   crosstalk -> delay -> lag -> hysteresis (play or Prandtl-Ishlinskii) ->
//   power law -> curvature ->
//   threshold -> saturation -> drift -> reading = gain (u + noise N(0,1)) + offset
// One channel is one fingertip treated as a single taxel under full coverage
// (like sim::PredictReading). Delay interpolates linearly in its history.
#pragma once

#include <cstdint>
#include <deque>
#include <random>
#include <utility>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/sim/sensor_model.h"

namespace tactforce::experiment {

class SensorChannel {
 public:
  // Validates the model (sim::ValidateSensorModel); `seed` drives the noise.
  static absl::StatusOr<SensorChannel> Create(const sim::SensorModel& model, uint64_t seed);

  // Reading (sensor units) for true normal force `force` (N) and shear (N)
  // at time t (s, non-decreasing).
  double Step(double t, double force, double shear = 0.0);
  // Force-domain value before noise, gain and offset (for tests).
  double last_force_domain() const { return last_u_; }

  const sim::SensorModel& model() const { return model_; }

 private:
  SensorChannel(const sim::SensorModel& model, uint64_t seed) : model_(model), rng_(seed) {}
  sim::SensorModel model_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  bool started_ = false;
  double t0_ = 0, lag_y_ = 0, lag_prev_u_ = 0, prev_t_ = 0, play_ = 0, last_u_ = 0;
  std::deque<std::pair<double, double>> history_;  // (t, u) for the delay
  std::vector<double> pi_state_;                   // Prandtl-Ishlinskii play operators
};

// The GeoDEx error ranges (Chen et al. RSS 2025, Sec. VI): activation
// threshold, hysteresis residual, force error and noise, each drawn
// uniformly per fingertip and trial.
struct ErrorRanges {
  double threshold_min = 0.1, threshold_max = 0.5;  // N
  double hysteresis_max = 0.2;                      // N, residual after release (= loop width / 2)
  double force_error_min = 0.1, force_error_max = 0.5;  // N, |error|, random sign
  double noise_min = 0.01, noise_max = 0.03;            // N, std. dev.
};
absl::Status ValidateErrorRanges(const ErrorRanges& r, const std::string& prefix = "errors.");

// One draw: threshold (shift 0: GeoDEx's activation jump), hysteresis
// width = 2 x residual, force error as the model's offset (gain 1, N), noise.
sim::SensorModel DrawGeoDexModel(const ErrorRanges& r, std::mt19937_64& rng);

}  // namespace tactforce::experiment
