// The tactile sensor model: per-taxel effects in the FORCE domain (N, s)
// followed by an affine map into the sensor's own units, plus noise.
//
// One taxel's reading for a true normal force f(t) and shear s(t):
//   u  = f + crosstalk * s                         (angled contact / shear)
//   u  = u(t - delay)                              (pure time delay)
//   u  = first-order lag, time constant `lag`
//   u  = play operator of loop width `hysteresis_width` (radius width/2)
//        or Prandtl-Ishlinskii hysteresis (the two forms are exclusive):
//        u = sum_k w_k play_{r_k}(u) / sum_k w_k, radii r_k = pi_thresholds
//        (N, 0 <= r_1 < ... < r_K; r = 0 is the identity), weights
//        pi_weights >= 0 (relative: normalised by their sum)
//   u  = full_scale * sign(u) |u / full_scale|^power_exponent
//                                                  (power law, 0 = off)
//   u  = u + curvature * u|u| / full_scale         (smooth nonlinearity)
//   u  = 0 if u < threshold, else u - threshold_shift * threshold
//        (shift 0: GeoDEx activation threshold, a jump; 1: continuous dead-zone)
//   u  = min(u, saturation)                        (0 = no saturation)
//   u  = u + drift * (t - t0)                      (t0 = first sample)
//   u  = u + partial_error * (1 - coverage)        (partial contact, in contact only)
//   reading = gain * (u + noise * N(0,1)) + offset
// Every effect parameter 0 = off; all off with gain 1, offset 0 = ideal.
// The fingertip sums taxel readings (GeoDEx IV-A), see simulate.h.
#pragma once

#include <map>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace tactforce::sim {

struct EffectParams {
  double threshold = 0;         // N, >= 0
  double threshold_shift = 0;   // [0, 1]
  double hysteresis_width = 0;  // N, >= 0 (full loop width; residual after release = width/2)
  double delay = 0;             // s (negative: reading leads, e.g. a clock offset)
  double lag = 0;               // s, >= 0
  double saturation = 0;        // N, > 0 to enable: no response above this force
  double curvature = 0;         // relative deviation at full_scale (e.g. 0.03 = 3 %)
  double full_scale = 20;       // N, > 0 (only scales curvature)
  double drift = 0;             // N/s
  double crosstalk = 0;         // N per N of shear
  // Power-law nonlinearity u -> full_scale * sign(u) |u/full_scale|^p
  // (p > 0; 0 = off; the gain absorbs the full_scale^(1-p) factor, so this
  // is reading = a * F^p + b in the force domain).
  double power_exponent = 0;
  // Prandtl-Ishlinskii hysteresis (empty = off; exclusive with
  // hysteresis_width): radii r_k (N, strictly increasing, >= 0) and
  // non-negative relative weights (normalised by their sum, which must be > 0).
  std::vector<double> pi_thresholds;
  std::vector<double> pi_weights;

  bool operator==(const EffectParams&) const = default;
};

struct SensorModel {
  std::string units = "N";   // the reading's units (free text: N, counts, uT)
  double gain = 1;           // reading units per N (may be negative)
  double offset = 0;         // reading units
  double noise = 0;          // N, additive Gaussian sigma per taxel under the contact patch
  double partial_error = 0;  // N, error of a partially covered taxel
  EffectParams effects;
  // Fitted models (audit output): 1-sigma uncertainty per field name.
  std::map<std::string, double> uncertainty;
  std::string source;  // free text: "simulated", "audit of run.csv", ...
};

// JSON (see README): a flat object, keys = the field names above plus
// "format": "tactforce.sensor_model.v1" and optional "uncertainty": {field: sigma}.
// Unknown keys are rejected (naming the key and line); missing keys keep the
// ideal default.
absl::StatusOr<SensorModel> SensorModelFromJson(const std::string& text, const std::string& source);
absl::StatusOr<SensorModel> LoadSensorModel(const std::string& path);
std::string SensorModelToJson(const SensorModel& model);
absl::Status SaveSensorModel(const SensorModel& model, const std::string& path);
// InvalidArgument naming the field for out-of-range values.
absl::Status ValidateSensorModel(const SensorModel& model);

// ---- The force-domain channel (deterministic, noise-free) ---------------
// Shared by the simulation (per taxel) and the audit (whole-sensor fits), so
// a fitted model re-simulates exactly as it was fitted.
struct ChannelInput {
  const double* t = nullptr;      // strictly increasing within a segment
  const double* force = nullptr;  // N
  const double* shear = nullptr;  // N, may be null (= 0)
  int n = 0;
  // Sample indices where an independent segment (trial) starts; dynamic state
  // (delay history, lag, play operator) restarts there. Empty = one segment.
  const std::vector<int>* segment_starts = nullptr;
  double t0 = 0;  // drift reference time
};
// out[i] = force-domain output (before gain/offset). out is resized.
void ApplyChannel(const EffectParams& p, const ChannelInput& in, std::vector<double>* out);

// Noise-free prediction of the sensor's reading for a measured reference:
// gain * channel + offset (single-taxel contact, full coverage).
std::vector<double> PredictReading(const SensorModel& model, const std::vector<double>& t,
                                   const std::vector<double>& reference,
                                   const std::vector<double>& shear,
                                   const std::vector<int>& segment_starts = {});

// Inverse of the static part: force estimate from a reading, for correcting
// readings (downstream use). Uses gain/offset, drift, crosstalk (needs shear;
// pass 0 if unknown), curvature, power law, threshold shift and saturation (clipped
// readings map to the saturation force). Dynamic effects are not inverted.
double CorrectReading(const SensorModel& model, double reading, double t_since_start, double shear);

}  // namespace tactforce::sim
