// Static friction from probing until slip (Sundaralingam & Hermans III-A).
// A fingertip holds a constant tangential force while its normal force is
// lowered until it slips; just before slip the force lies on the friction
// cone, so mu = tan(acos(f_hat . n)) = |f_t| / f_n.
//
// Object frame, SI units. Forces are those the probe applies TO the object;
// n is the unit surface normal pointing INTO the object.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/io/csv.h"
#include "tactforce/io/mesh.h"
#include "tactforce/planner/types.h"

namespace tactforce::estimator {

using planner::Vec3;

struct FrictionSample {
  double t = 0.0;                     // s
  Vec3 force = Vec3::Zero();          // N
  Vec3 contact_point = Vec3::Zero();  // m
  std::optional<bool> slip;           // explicit slip flag, when measured
};

struct FrictionTrial {
  std::string name;
  std::vector<FrictionSample> samples;
  std::optional<Vec3> normal;  // else the mesh's nearest triangle is used
};

enum class PreSlipForce {
  kWindowAverage,  // the paper: mean of `window` samples ending before onset
  kLinearFit,      // ours: per-component line over the `fit_window` samples
                   // of that window, evaluated at the onset (no ramp lag, less noise)
};

struct FrictionOptions {
  double slip_distance = 1e-3;  // m of tangential travel from the trial start
  int window = 5;               // samples averaged (kWindowAverage)
  int fit_window = 300;         // samples fitted (kLinearFit)
  PreSlipForce pre_slip = PreSlipForce::kWindowAverage;
  double min_normal_force = 0.05;  // N
  // Onset back-tracking: speed noise level = median + k * 1.4826 MAD of the
  // tangential contact-point speeds before detection.
  double noise_k = 6.0;
  // ... and never below this fraction of `slip_distance`: with noise-free
  // contact points the MAD is ~0 and sub-micrometre pre-slip deformation
  // (soft contacts, a real pad's shear) would be read as the onset.
  double min_onset_fraction = 0.01;
  std::optional<io::TriangleMesh> mesh;
  // Polled between trials; once true the estimate stops with
  // absl::Cancelled("interrupted after i of N trials"). May be empty.
  std::function<bool()> interrupt;
};

struct TrialFriction {
  std::string name;
  bool slipped = false;
  bool valid = false;        // false: no estimate (message says why)
  double mu = 0.0;           // slipped: estimate; else lower bound
  double mu_sigma = 0.0;     // slipped: standard error of mu over the pre-slip samples
  bool lower_bound = false;  // no slip: mu >= the largest |f_t| / f_n seen
  double slip_time = 0.0;    // s, onset: the last sample at rest before the motion
  int slip_index = -1;       // onset sample (the window ends one sample before it)
  int detection_index = -1;  // where travel/flag first said "slip"
  double force_angle = 0.0;  // rad, acos(f_hat . n) before slip
  Vec3 normal = Vec3::Zero();
  int mesh_triangle = -1;
  std::string message;
};

struct FrictionEstimate {
  std::vector<TrialFriction> trials;
  // Over valid slipped trials.
  double median = 0.0, mean = 0.0, iqr = 0.0;
  // Std. dev. of mu: over the trials (sample, n - 1) when two or more, else
  // the one trial's own mu_sigma; 0 when none slipped.
  double mu_sigma = 0.0;
  int count = 0;
};

// Errors name the field: "trials: empty", "trials[2].samples[7].t: not
// increasing", "trials[0].normal: zero length", "trials[1]: no normal and no
// mesh", mesh errors from io::ValidateMesh.
absl::StatusOr<FrictionEstimate> EstimateFriction(const std::vector<FrictionTrial>& trials,
                                                  const FrictionOptions& options = {});

// CSV `t,fx,fy,fz,px,py,pz[,slip]` -> trial (name = source).
absl::StatusOr<FrictionTrial> FrictionTrialFromCsv(const io::CsvTable& table);

// ---- simulator for tests and users ---------------------------------------
struct FrictionSimOptions {
  double mu = 0.5;
  int trials = 10;
  double force_noise = 0.05;      // N, std. dev. per force component
  double position_noise = 2e-5;   // m, std. dev. per position component
  double rate = 200.0;            // Hz
  double tangential_force = 3.0;  // N, held constant
  double ramp = 0.5;              // N/s, normal-force decrease
  double slide_speed = 0.02;      // m/s reached after slip
  // After slip the probe accelerates with (mu_s - mu_k) f_n / probe_mass
  // (mu_k = 0.8 mu): static friction breaks abruptly.
  double probe_mass = 0.05;          // kg
  double duration_after_slip = 0.3;  // s
  bool write_slip_flags = false;
  uint64_t seed = 1;
};

struct SimulatedFriction {
  std::vector<FrictionTrial> trials;
  std::vector<double> true_slip_time;  // s
  Vec3 normal;                         // the surface normal used
};

SimulatedFriction SimulateFriction(const FrictionSimOptions& options);

}  // namespace tactforce::estimator
