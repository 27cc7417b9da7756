// SensorChannel (sensor_channel.h): the sensor model evaluated one sample at
// a time inside the control loop, with its own noise stream and the state of
// hysteresis, delay, lag and drift; and the GeoDEx error-range draws.
#include "tactforce/experiment/sensor_channel.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {

absl::StatusOr<SensorChannel> SensorChannel::Create(const sim::SensorModel& model, uint64_t seed) {
  TF_RETURN_IF_ERROR(sim::ValidateSensorModel(model));
  return SensorChannel(model, seed);
}

double SensorChannel::Step(double t, double force, double shear) {
  const sim::EffectParams& p = model_.effects;
  double u = force + (p.crosstalk != 0 ? p.crosstalk * shear : 0.0);
  if (!started_) {
    started_ = true;
    t0_ = t;
    prev_t_ = t;
    lag_y_ = u;
    lag_prev_u_ = u;
    play_ = 0;  // starts released, like ApplyChannel
  }
  if (p.delay != 0) {
    history_.emplace_back(t, u);
    const double tq = t - p.delay;
    // Drop samples no longer needed (keep one before tq).
    while (history_.size() > 2 && history_[1].first <= tq) history_.pop_front();
    if (tq <= history_.front().first) {
      u = history_.front().second;
    } else if (tq >= history_.back().first) {
      u = history_.back().second;
    } else {
      for (size_t i = 0; i + 1 < history_.size(); ++i) {
        const auto& a = history_[i];
        const auto& b = history_[i + 1];
        if (tq <= b.first) {
          const double s = (tq - a.first) / std::max(1e-15, b.first - a.first);
          u = a.second + s * (b.second - a.second);
          break;
        }
      }
    }
  }
  if (p.lag > 0) {
    const double h = t - prev_t_;
    if (h > 0) {
      const double e = std::exp(-h / p.lag);
      const double slope = (u - lag_prev_u_) / h;
      lag_y_ = u - p.lag * slope + e * (lag_y_ - lag_prev_u_ + p.lag * slope);
    }
    lag_prev_u_ = u;
    u = lag_y_;
  }
  prev_t_ = t;
  if (p.hysteresis_width > 0) {
    const double r = 0.5 * p.hysteresis_width;
    play_ = std::max(u - r, std::min(u + r, play_));
    u = play_;
  } else if (!p.pi_thresholds.empty() && p.pi_thresholds.size() == p.pi_weights.size()) {
    // Prandtl-Ishlinskii: weighted mean of play operators, all starting released.
    pi_state_.resize(p.pi_thresholds.size(), 0.0);
    double y = 0, wsum = 0;
    for (size_t k = 0; k < pi_state_.size(); ++k) {
      const double r = p.pi_thresholds[k];
      pi_state_[k] = std::max(u - r, std::min(u + r, pi_state_[k]));
      y += p.pi_weights[k] * pi_state_[k];
      wsum += p.pi_weights[k];
    }
    if (wsum > 0) u = y / wsum;
  }
  if (p.power_exponent > 0 && p.power_exponent != 1 && u != 0)
    u = (u < 0 ? -p.full_scale : p.full_scale) *
        std::pow(std::abs(u) / p.full_scale, p.power_exponent);
  if (p.curvature != 0) u += p.curvature / p.full_scale * u * std::abs(u);
  if (p.threshold > 0) u = (u < p.threshold) ? 0.0 : u - p.threshold_shift * p.threshold;
  if (p.saturation > 0 && u > p.saturation) u = p.saturation;
  if (p.drift != 0) u += p.drift * (t - t0_);
  last_u_ = u;
  const double noise = model_.noise > 0 ? model_.noise * gauss_(rng_) : 0.0;
  return model_.gain * (u + noise) + model_.offset;
}

absl::Status ValidateErrorRanges(const ErrorRanges& r, const std::string& prefix) {
  auto range = [&](const char* lo_name, double lo, const char* hi_name, double hi) -> absl::Status {
    if (!(lo >= 0 && std::isfinite(lo)))
      return absl::InvalidArgumentError(
          absl::StrFormat("%s%s: must be >= 0, got %g", prefix, lo_name, lo));
    if (!(hi >= lo && std::isfinite(hi)))
      return absl::InvalidArgumentError(
          absl::StrFormat("%s%s: must be >= %s (%g), got %g", prefix, hi_name, lo_name, lo, hi));
    return absl::OkStatus();
  };
  TF_RETURN_IF_ERROR(range("threshold_min", r.threshold_min, "threshold_max", r.threshold_max));
  TF_RETURN_IF_ERROR(range("hysteresis_max", 0.0, "hysteresis_max", r.hysteresis_max));
  TF_RETURN_IF_ERROR(
      range("force_error_min", r.force_error_min, "force_error_max", r.force_error_max));
  TF_RETURN_IF_ERROR(range("noise_min", r.noise_min, "noise_max", r.noise_max));
  return absl::OkStatus();
}

sim::SensorModel DrawGeoDexModel(const ErrorRanges& r, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto draw = [&](double lo, double hi) { return lo + (hi - lo) * u01(rng); };
  sim::SensorModel m;
  m.source = "GeoDEx error ranges";
  m.effects.threshold = draw(r.threshold_min, r.threshold_max);
  m.effects.hysteresis_width = 2 * draw(0.0, r.hysteresis_max);
  const double sign = u01(rng) < 0.5 ? -1.0 : 1.0;
  m.offset = sign * draw(r.force_error_min, r.force_error_max);
  m.noise = draw(r.noise_min, r.noise_max);
  return m;
}

}  // namespace tactforce::experiment
