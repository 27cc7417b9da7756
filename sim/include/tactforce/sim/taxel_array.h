// A streaming 42-taxel fingertip (GeoDEx IV-A) with a draw per taxel of the
// paper's error ranges: activation threshold, hysteresis, force error under
// partial coverage or misaligned force, noise and saturation. The paper's own
// simulation used one characterisation for every taxel; here each taxel has
// its own draw.
//
// Per sample (TaxelArray::Step) the input is the contact point and the 3D
// force the object exerts on the fingertip, both in the fingertip frame of
// DefaultFingertip (simulate.h). A Hertz contact patch of radius
//   a = patch_radius_coeff * cbrt(|F| / 1 N), capped at patch_radius_max,
// with pressure ~ sqrt(1 - r^2 / a^2) lies in the surface's tangent plane at
// the contact point; every point of it belongs to its nearest taxel (the
// taxels tile the surface), so taxel i's share is the fraction of the
// patch's force on its own cell (shares sum to 1), and its load is
//   load_i = share_i * |F| * max(0, cos_i),  cos_i = -F.n_i / |F|.
// The pressure under every point rises with |F|, so at a fixed contact no
// taxel's load falls as the force grows (the readings stay monotone).
// Each taxel then runs, in this order:
//   activation: inactive until load >= threshold (a jump of about threshold);
//   hysteresis: a play operator of radius `hysteresis` started at the load on
//     activation, relaxing towards the load with time constant
//     hysteresis_decay; after unloading the taxel keeps reading the residual
//     (<= hysteresis) until it relaxes below 0.01 N, when it deactivates;
//   saturation: reading <= saturation;
//   force error: + force_error * max(1 - coverage, 1 - cos) while loaded,
//     the sum clipped at 0
//     (coverage = the fraction of the taxel's disc inside the patch);
//   noise: + noise * N(0, 1) while active.
// The fingertip output is simulate.h's AggregateFingertip: force = sum of
// readings, location = force-weighted mean position, normal = normalised
// force-weighted mean normal. SI units throughout.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "Eigen/Core"
#include "absl/status/statusor.h"
#include "tactforce/sim/simulate.h"

namespace tactforce::sim {

// The ranges each taxel's parameters are drawn from (uniform), and the patch.
struct TaxelRanges {
  double threshold_min = 0.1, threshold_max = 0.5;  // N, activation threshold
  double hysteresis_max = 0.2;                      // N, residual after release, drawn in [0, max]
  double hysteresis_decay = 2.0;  // s, relaxation time constant (0 = the residual stays)
  double force_error_min = 0.1, force_error_max = 0.5;  // N, magnitude, random sign per taxel
  double noise_min = 0.01, noise_max = 0.03;            // N, std. dev.
  double saturation = 20;                               // N per taxel, > 0
  double patch_radius_coeff = 0.003;                    // m at 1 N (radius grows as cbrt(force))
  double patch_radius_max = 0.008;                      // m
  double taxel_radius = 0.0025;                         // m, each taxel's sensing disc
  bool operator==(const TaxelRanges&) const = default;
};
// InvalidArgument naming `prefix` + the field: negative or non-finite values,
// max < min, saturation <= threshold_max, a zero patch.
absl::Status ValidateTaxelRanges(const TaxelRanges& r, const std::string& prefix = "");

// JSON: {"format": "tactforce.taxel_ranges.v1", field: number, ...}; missing
// fields keep the defaults above; unknown fields and out-of-range values are
// errors naming source, line and field.
absl::StatusOr<TaxelRanges> TaxelRangesFromJson(const std::string& text, const std::string& source);
absl::StatusOr<TaxelRanges> LoadTaxelRanges(const std::string& path);
std::string TaxelRangesToJson(const TaxelRanges& r);

// One taxel's draw.
struct TaxelParams {
  double threshold = 0;    // N
  double hysteresis = 0;   // N, play radius (= residual after release)
  double force_error = 0;  // N, signed
  double noise = 0;        // N
};

// Where the force lands: per taxel load (N), coverage and misalignment in [0, 1].
struct TaxelLoads {
  std::vector<double> load, coverage, misalignment;
  double patch_radius = 0;  // m
};
TaxelLoads ComputeTaxelLoads(const std::vector<Taxel>& taxels, const TaxelRanges& r,
                             const Eigen::Vector3d& contact, const Eigen::Vector3d& force);

// The point of the fingertip's surface nearest to `p` (fingertip frame of
// DefaultFingertip, m) and the outward surface normal there: the hemisphere
// above z = body_length, the cylinder below it. A sensed location (a
// force-weighted mean of taxel positions, which lies inside the surface)
// placed back on the known surface; its normal is the surface's.
Taxel ProjectOntoFingertip(const FingertipGeometry& g, const Eigen::Vector3d& p);

// The array's angular resolution on its dome (deg): the largest angle, seen
// from the tip's centre (0, 0, body_length), from a point of the hemisphere
// (polar angle <= 90 deg) to its nearest taxel. A contact normal sensed from
// the taxels can be off by about this much where no neighbour shares the load.
double DomeResolutionDeg(const std::vector<Taxel>& taxels, const FingertipGeometry& g = {});

struct TaxelArrayReading {
  std::vector<double> load;     // N, noise-free true load per taxel
  std::vector<double> reading;  // N, per taxel
  FingertipReading fingertip;   // from `reading` (fingertip frame)
  double true_force = 0;        // N, |F|
  int active = 0;               // taxels reading
};

class TaxelArray {
 public:
  // Validates `ranges`; `seed` drives the draws and the noise.
  static absl::StatusOr<TaxelArray> Create(const TaxelRanges& ranges, uint64_t seed,
                                           const FingertipGeometry& geometry = {});
  // t in s (non-decreasing); contact: point on the surface (fingertip frame,
  // m); force: on the fingertip, pressing into it (fingertip frame, N); a zero
  // force is no contact.
  const TaxelArrayReading& Step(double t, const Eigen::Vector3d& contact,
                                const Eigen::Vector3d& force);

  const std::vector<Taxel>& taxels() const { return taxels_; }
  const std::vector<TaxelParams>& params() const { return params_; }
  const TaxelRanges& ranges() const { return ranges_; }
  const TaxelArrayReading& last() const { return out_; }

 private:
  TaxelArray(const TaxelRanges& r, uint64_t seed, const FingertipGeometry& g);
  TaxelRanges ranges_;
  std::vector<Taxel> taxels_;
  std::vector<TaxelParams> params_;
  std::mt19937_64 noise_rng_;
  std::normal_distribution<double> gauss_{0.0, 1.0};
  std::vector<char> active_;
  std::vector<double> play_;
  double prev_t_ = 0;
  bool started_ = false;
  TaxelArrayReading out_;
};

}  // namespace tactforce::sim
