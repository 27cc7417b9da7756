// Tactile fingertip simulation: a taxel fingertip (default 42 taxels over a
// hemispherical tip and a cylindrical body), per-taxel effects from a
// SensorModel, fingertip-level force/location/normal as in GeoDEx IV-A:
//   raw force  = sum of taxel readings (in N, before gain/offset)
//   location   = force-weighted mean of taxel positions
//   normal     = normalised force-weighted mean of taxel normals
// and force profiles (press-release, ramp, random) to drive it.
//
// The measured-data CSV written by WriteSimRun is the audit's input format:
//   run.csv:       t,reference,reading,shear,trial
//   fingertip.csv: t,force,px,py,pz,nx,ny,nz    (fingertip level, N and m)
//   model.json:    the true sensor model (sensor_model.h)
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "Eigen/Core"
#include "absl/status/statusor.h"
#include "tactforce/sim/sensor_model.h"

namespace tactforce::sim {

struct Taxel {
  Eigen::Vector3d position;  // fingertip frame, m
  Eigen::Vector3d normal;    // unit, outward
};

struct FingertipGeometry {
  double radius = 0.012;      // m, tip hemisphere and body cylinder
  double body_length = 0.03;  // m, cylinder along +z from z=0; tip centre at z=body_length
};
// 42 taxels: hemisphere apex + rings of 6 (30 deg) and 10 (60 deg) = 17,
// cylinder 5 rings x 5 = 25. Index 0 is the apex.
std::vector<Taxel> DefaultFingertip(const FingertipGeometry& g = {});

struct FingertipReading {
  double force = 0;  // N, sum of taxel readings
  Eigen::Vector3d location = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // zero when force ~ 0
};
// Taxel readings in N (force domain). Weights are the readings clipped at 0.
FingertipReading AggregateFingertip(const std::vector<Taxel>& taxels,
                                    const std::vector<double>& readings);

enum class Profile { kPressRelease, kRamp, kRandom };
absl::StatusOr<Profile> ParseProfile(std::string_view name);  // "press-release", "ramp", "random"
const char* ToString(Profile p);

struct SimOptions {
  Profile profile = Profile::kPressRelease;
  double seconds = 20;
  double rate = 200;  // Hz, output sample rate
  uint64_t seed = 1;
  double min_peak = 1.0;  // N, per-press peak force drawn in [min_peak, max_peak]
  double max_peak = 8.0;
  double max_shear_ratio = 0.6;  // shear = ratio * force, ratio per press in [0, max]
  double reference_noise = 0;    // N, sigma on the reference column
  int contact_taxel = 0;         // taxel at the contact centre
  double contact_radius = 0;     // m; 0 = the whole contact on one taxel
  int oversample = 4;            // internal steps per output sample (exact delay/lag)
  int trial = 0;                 // written to the 'trial' column
};

struct SimRun {
  std::vector<double> t, reference, reading, shear;
  std::vector<double> true_force;           // noise-free normal force (N)
  std::vector<FingertipReading> fingertip;  // per sample
  SensorModel model;
  SimOptions options;
};

// Errors: InvalidArgument naming the option or model field.
absl::StatusOr<SimRun> SimulateSensor(const SensorModel& model, const SimOptions& options);

// Writes dir/run.csv, dir/fingertip.csv and dir/model.json (creates dir).
absl::Status WriteSimRun(const SimRun& run, const std::string& dir);
std::string SimRunCsv(const SimRun& run);  // run.csv text

}  // namespace tactforce::sim
