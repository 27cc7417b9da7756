// Friction probed inside a grasp (Sundaralingam & Hermans III-A, IV-A), in
// MuJoCo. Three floating fingertips hold a box to the holding plan of
// planner::PlanFrictionProbe (impedance: PD targets offset by the planned
// force over the stiffness, plus the force admittance of `experiment grasp`);
// a fourth fingertip on the box's top face pushes with a constant tangential
// force while its normal force ramps down until it slips. Its contact force
// goes through a 3-axis tactile force model (bias + noise per axis); its
// contact point is expressed in the object frame through the tracked object
// pose; the surface normal is the nearest triangle of the box's mesh;
// mu = tan(acos(f_hat . n)) (eq. 5) through estimator::EstimateFriction.
// Ground truth per surface: the slope method (slope.h) on the same pair.
//
// Object frame: origin at the box centre, axes along its edges, +z up at
// rest. The probe sits on the +z face and pushes towards +x. In the air the
// thumb opposes it from the -z face and two fingers pinch the x faces; on a
// table the thumb is on the -x face and two fingers on the +x face. SI units.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "absl/status/statusor.h"
#include "tactforce/experiment/slope.h"
#include "tactforce/io/mesh.h"

namespace tactforce::experiment {

// A fingertip/object surface pair and its (MJCF) Coulomb friction.
struct SurfacePair {
  std::string name;
  double mu = 0.5;
};
// At least ten named pairs, mu in [0.3, 1.0] (representative values, not
// measurements; what matters is that MuJoCo is configured with them).
const std::vector<SurfacePair>& BuiltInSurfaces();
// Non-empty, every mu in [0.1, 1.5]; InvalidArgument "surfaces[2].mu: ...".
absl::Status ValidateSurfaces(const std::vector<SurfacePair>& surfaces);

// A rigid box: full edge lengths, mass, CoM offset from the box centre; the
// inertia is that of the uniform box about its centre, moved to the CoM.
struct ProbeObject {
  std::string name;
  Eigen::Vector3d size = Eigen::Vector3d(0.08, 0.06, 0.05);  // m
  double mass = 0.15;                                        // kg
  Eigen::Vector3d com_offset = Eigen::Vector3d::Zero();      // m, object frame
};
const std::vector<ProbeObject>& BuiltInProbeObjects();
// InvalidArgument naming the field ("size[1]: ...", "mass: ...", "com_offset: ...").
absl::Status ValidateProbeObject(const ProbeObject& o);
// A built-in by name; NotFound listing the names.
absl::StatusOr<ProbeObject> FindProbeObject(const std::string& name);
// {"name"?, "size": [x, y, z], "mass": m, "com_offset"?: [x, y, z]};
// unknown keys are errors; every error names the field (and source:line).
absl::StatusOr<ProbeObject> ProbeObjectFromJson(const std::string& text, const std::string& source);
// The box's closed triangle mesh in the object frame (12 triangles).
io::TriangleMesh BoxMesh(const Eigen::Vector3d& size);

struct ProbeConfig {
  ProbeObject object;
  bool on_table = false;      // the box rests on a table (the paper's Fig. 1)
  double table_mu = 0.5;      // box/table
  double force_sigma = 0.05;  // N, tactile noise per axis per sample
  double force_bias = 0.02;   // N, std. dev. of the per-trial constant bias per axis
  // m, tactile contact-point noise per axis per sample (the friction
  // simulator's default, estimator::FrictionSimOptions::position_noise). With
  // exactly noise-free points EstimateFriction's onset threshold (median +
  // k MAD of the quiet travel) collapses to MuJoCo's sub-micrometre creep.
  double contact_sigma = 2e-5;
  double hold_scale = 1.0;           // scales the planned holding forces (negative control < 1)
  double max_motion = 0.001;         // m, object travel allowed before slip
  double max_rotation_deg = 1;       // deg, object rotation allowed before slip
  double probe_travel_stop = 0.003;  // m of probe travel on the object that ends a trial
  double kp = 10000;                 // N/m, holding fingertip stiffness (damping ratio 1)
  // Per 200 Hz tick: the 3D force admittance of `experiment grasp` (which
  // uses 0.2), slower here so the hold stays stiff; 0: impedance only.
  double admittance_gain = 0.05;
  double fingertip_radius = 0.012, fingertip_mass = 0.05;
  double confidence = 1.0;  // planner kappa
  // N, the planner's normal-force sigma of a holding fingertip: the grip
  // margin (README: 0.05 and 0.3 let the box creep past 1 mm / 1 deg).
  double plan_sigma = 1.0;
  uint64_t seed = 1;
  // The probe schedule (probe_tangential, probe_ramp, probe_start_ratio on
  // the configured mu, sample_rate), EstimateFriction's options and the
  // physics: shared with the plate probe so both read the same schedule.
  SlopeConfig slope;
};
// InvalidArgument naming the field.
absl::Status ValidateProbeConfig(const ProbeConfig& c);

struct ProbeTrialResult {
  std::string surface;
  int trial = 0;
  double mu_true = 0;       // MJCF
  double mu_slope = 0;      // slope method on the same pair
  double mu_estimated = 0;  // eq. 5 (0 when not valid)
  double error = 0;         // mu_slope - mu_estimated (the paper's mu_gt - mu)
  bool valid = false;
  std::string invalid_reason;
  double object_motion_mm = 0;  // max before slip (whole probe if no slip)
  double object_rotation_deg = 0;
  bool slip_detected = false;
  int mesh_triangle = -1;
  double wall_seconds = 0;
};

struct SurfaceSummary {
  std::string surface;
  double mu_true = 0, mu_slope = 0;
  double mu_plate_probe = 0;  // RunSlopeAndProbe's plate probe (noise free)
  bool plate_probe_valid = false;
  int trials = 0, valid = 0;
  double median_estimate = 0, median_signed_error = 0, median_abs_error = 0;
  double mean_estimate = 0;
  double in_grasp_minus_plate = 0;  // mean valid estimate - plate probe
};

struct ProbeSummary {
  int trials = 0, valid = 0, slip_detected_valid = 0;
  double median_signed_error = 0, median_abs_error = 0;  // pooled valid trials
  double mean_in_grasp_minus_plate = 0;                  // mean over surfaces with both
  std::vector<SurfaceSummary> per_surface;
};

struct ProbeReport {
  std::vector<ProbeTrialResult> trials;
  ProbeSummary summary;
  double wall_seconds = 0;
};

// One trial on one surface; `mu_slope` is copied into the result. Trial k of
// seed s draws the same sensor bias, noise and probe position whatever else runs.
absl::StatusOr<ProbeTrialResult> RunProbeTrial(const ProbeConfig& c, const SurfacePair& surface,
                                               int trial, double mu_slope);

// Per surface: the slope method and the plate probe (RunSlopeAndProbe), then
// `trials` in-grasp trials; the summary. `progress(done, total)` after each
// trial (may be empty).
absl::StatusOr<ProbeReport> RunProbeExperiment(const ProbeConfig& c,
                                               const std::vector<SurfacePair>& surfaces, int trials,
                                               const std::function<void(int, int)>& progress = {});

}  // namespace tactforce::experiment
