// In-hand inertia data source (Sundaralingam & Hermans, Sec. IV-B and VI):
// four floating fingertips hold a box and move it along an exciting
// trajectory in MuJoCo, with holding forces from planner::PlanTrajectory; the
// run is logged at `rate` through a tactile force model and an object
// tracker as the inertia samples `tactforce inertia` reads.
//
// Frames and units: SI; the object frame is the one of the inertia CSV
// (inertia/types.h); contact forces are those APPLIED TO THE OBJECT.
//
// Built-in objects box_0..box_4 (the paper's Table II ground truth): mass
// 0.115 / 0.179 / 0.179 / 0.131 / 0.147 kg and the CoM of the table (object
// frame, m). Convention for the table's inertia: it is about the OBJECT
// ORIGIN with products listed as +sum(m x y) (they equal m cx cy, m cx cz,
// m cy cz to the printed digits); removing the parallel-axis terms leaves a
// diagonal inertia about the CoM, which is that of a uniform box centred on
// the CoM, axis-aligned with the object frame; that box is the object's
// geometry (and mesh).
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "tactforce/experiment/physics.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/types.h"
#include "tactforce/io/mesh.h"

namespace tactforce::experiment {

// kVision: see VisionTrackerModel. kKinematic: the object rigidly attached
// at the first sample to fingertip 0 (position) and to the hand's rotation
// (Kabsch over the fingertip centres not in a break): slip becomes pose
// drift; a break of contact 0 drags the tracked pose with the fingertip.
enum class Tracker { kVision, kKinematic };
const char* ToString(Tracker tracker);                        // "vision", "kinematic"
absl::StatusOr<Tracker> ParseTracker(std::string_view text);  // errors name "tracker"

// A point mass inside the object (non-uniform objects).
struct PointMass {
  double mass = 0;                                     // kg
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  // object frame (m)
};

// A box-shaped object: the uniform box (mass minus the point masses) plus
// the point masses.
struct InHandObject {
  std::string name;
  Eigen::Vector3d dimensions =
      Eigen::Vector3d(0.18, 0.07, 0.07);             // edge lengths along object x,y,z (m)
  Eigen::Vector3d center = Eigen::Vector3d::Zero();  // box centre in the object frame (m)
  double mass = 0.1;                                 // total (kg)
  std::vector<PointMass> point_masses;
};

std::vector<std::string> BuiltInInHandObjects();  // box_0 .. box_4
// InvalidArgument "object: unknown 'x' (expected box_0, ...)".
absl::StatusOr<InHandObject> BuiltInInHandObject(const std::string& name);
// {"name": optional, "dimensions": [x,y,z] (m, each in (0.02, 0.5]),
//  "mass": kg (> 0, total), "center": optional [x,y,z] (m),
//  "point_masses": optional [{"mass": kg > 0, "position": [x,y,z]}...]
//  (inside the box; their sum < mass)}. Errors name the source and key
// ("obj.json: mass: must be > 0, got -1").
absl::StatusOr<InHandObject> ParseInHandObjectJson(const std::string& text,
                                                   const std::string& source);
absl::StatusOr<InHandObject> ReadInHandObjectFile(const std::string& path);
absl::Status ValidateInHandObject(const InHandObject& object,
                                  const std::string& prefix = "object.");
// Mass, CoM and inertia about the CoM of the box plus its point masses.
inertia::InertialParameters InHandObjectInertia(const InHandObject& object);
// The box as a closed, outward-facing triangle mesh (object frame, m).
io::TriangleMesh InHandObjectMesh(const InHandObject& object);

// Tactile force model: the reading (fingertip frame = world axes) is
//   f_read = f_true + b_i(t) + n, b_i a drifting bias per contact and axis
//   (Ornstein-Uhlenbeck: stationary std bias_sigma, time constant
//   bias_time), n ~ N(0, s(|f|)^2) per axis, s(f) = noise_floor + noise_slope |f|;
// the REPORTED per-sample sigma (per component) is sqrt(bias_sigma^2 + s^2),
// so about 68 % of component errors are within it. A contact that is off
// reads exactly zero. The contact point gets isotropic noise point_sigma.
struct TactileForceModel {
  std::string name = "biotac";
  double bias_sigma = 0.0155;  // N
  double bias_time = 2.0;      // s
  double noise_floor = 0.010;  // N
  double noise_slope = 0.013;  // per N of |f|
  double point_sigma = 0.001;  // m
};
// "biotac" (defaults above, chosen to give the paper's medians: 0.03 N in
// magnitude, 1.28 deg in angle, at this source's 2-3 N forces) or "ideal".
absl::StatusOr<TactileForceModel> NamedForceModel(const std::string& name);

// Vision tracker (the paper's DART on a depth camera): assumptions of ours,
// not measured: one pose per logged sample, position noise 1 mm and
// orientation noise 0.5 deg (per axis, white), dropouts that start with
// `dropout_probability` per sample and last 1..dropout_max_samples samples,
// during which the tracker repeats its last pose.
struct VisionTrackerModel {
  double position_sigma = 0.001;       // m
  double orientation_sigma_deg = 0.5;  // deg
  double dropout_probability = 0.01;
  int dropout_max_samples = 5;
};

struct ContactBreak {
  int contact = 0;        // 0..3
  double start = 0;       // s since logging began
  double duration = 0.5;  // s
};

// An external push on the object at its CoM (world frame): injects slip.
struct Push {
  double start = 0, duration = 0.05;                // s since logging began
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // N
};

struct InHandConfig {
  std::string object = "box_0";        // a built-in name (ignored when `custom` is set)
  std::optional<InHandObject> custom;  // e.g. from ReadInHandObjectFile
  Tracker tracker = Tracker::kVision;
  double duration = 10;  // s logged (the motion ramps in over the first second)
  double rate = 100;     // Hz, log rate
  uint64_t seed = 1;
  std::string force_model = "biotac";                   // NamedForceModel
  std::optional<TactileForceModel> custom_force_model;  // overrides `force_model`
  bool ideal_forces = false;                            // log the true forces and points
  bool ideal_tracking = false;                          // log the true pose
  VisionTrackerModel vision;
  double support_fraction = 0;  // of the weight carried by an unsensed support, [0, 0.9]
  std::vector<ContactBreak> breaks;
  std::vector<Push> pushes;
  // Excitation: ExcitationTrajectory::Default() scaled to a hand's workspace.
  double position_scale = 0.3;     // x 0.1 m amplitudes
  double orientation_scale = 0.4;  // x 0.8 rad amplitudes
  double friction = 1.0;           // MuJoCo fingertip/object mu
  double plan_friction = 0.6;      // mu the planner assumes (margin)
  double min_normal_force = 2.0;   // N
  double fingertip_radius = 0.012, fingertip_mass = 0.05, kp = 10000;
  double control_rate = 200;  // Hz: plans, admittance
  double settle = 0.5;        // s held still before logging
  PhysicsSettings physics = [] {
    PhysicsSettings p;
    p.condim_fingertip = 3;  // point contacts, as the inertia model assumes
    return p;
  }();
};

// InvalidArgument naming the field ("rate: must be > 0, got 0").
absl::Status ValidateInHandConfig(const InHandConfig& config);

struct InHandEvent {
  double t = 0;  // s since logging began
  std::string
      kind;  // contact_lost, contact_made, break_start, break_end, push, tracker_dropout, ...
  int contact = -1;  // -1: the object / tracker
  std::string detail;
};

// Ground truth per logged sample (what the sensors see before their models).
struct InHandTruthRow {
  double t = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  std::vector<Eigen::Vector3d> force;  // per contact, applied to the object, object frame (N)
  std::vector<Eigen::Vector3d> point;  // per contact, object frame (m)
  std::vector<double>
      slip_mm;  // contact point travel in the object frame since first made (0 when off)
  std::vector<bool> in_contact;
};

struct InHandStats {
  // Logged true forces vs the truth parameters with MuJoCo's accelerations.
  double ne_residual_force_max = 0, ne_residual_force_rms = 0;  // N
  double ne_residual_torque_rms = 0;                            // N m
  double mg = 0;                                                // N
  // Object-frame net contact force: std (norm of per-axis stds) in hand, on
  // a wrist sensor along the default (arm) excitation, and along this
  // run's own trajectory (equal by Newton: a check).
  double net_force_std = 0, wrist_net_force_std = 0, wrist_same_trajectory_net_force_std = 0;
  // Force model: medians over samples in contact, share |error| <= sigma.
  double median_magnitude_error = 0, median_angle_error_deg = 0, sigma_coverage = 0;
  double max_slip_mm = 0;
  double tracker_position_error_max_mm = 0, tracker_position_error_final_mm = 0;
  double tracker_rotation_error_max_deg = 0;
  double slip_tracker_correlation =
      0;  // Pearson r of tracker position error vs max slip per sample
  int tracker_dropouts = 0;
  int contact_losses = 0;       // unscheduled
  double min_normal_force = 0;  // N, over contacts in contact and not in a break
  double wall_seconds = 0;
};

struct InHandRun {
  std::string object_name;
  InHandObject object;
  inertia::InertiaSamples samples;  // what the sensors and tracker logged
  inertia::InertialParameters truth;
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.81);  // world
  std::shared_ptr<const io::TriangleMesh> mesh;
  std::vector<Eigen::Vector3d> hull;  // the box corners
  double tracker_position_sigma = 0,
         tracker_orientation_sigma = 0;  // what the tracker assumed (m, rad)
  std::vector<InHandTruthRow> truth_log;
  std::vector<Eigen::Vector3d> tracker_error;  // per sample: tracked - true position (world, m)
  std::vector<InHandEvent> events;
  InHandStats stats;
};

// Runs the simulation. `progress` gets the fraction done (0..1).
absl::StatusOr<InHandRun> RunInHand(const InHandConfig& config,
                                    const std::function<void(double)>& progress = {});

// Fit options matching a run: gravity, hull, mesh, and the tracker's pose
// noise (force noise comes from the per-sample sigmas).
inertia::InertiaOptions InHandFitOptions(const InHandRun& run, inertia::InertiaMethod method);

// Writes DIR/inertia.csv, truth.json, events.csv, truth_log.csv and the
// object's mesh DIR/mesh.obj (creates DIR).
absl::Status WriteInHandRun(const InHandRun& run, const std::string& dir);

}  // namespace tactforce::experiment
