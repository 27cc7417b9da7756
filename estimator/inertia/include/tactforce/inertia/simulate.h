// Simulated inertia data sets (`tactforce simulate inertia`): a rigid object
// with known (m, c, H) moved along an exciting trajectory (sums of sinusoids
// in position and in Z-Y-X Euler angles), with
//   * kWristWrench: the wrench a wrist force/torque sensor applies, or
//   * kInHand: num_contacts fingertip forces from the tactforce planner
//     (geometric backend, friction cones, minimum squeeze), so the forces are
//     physically plausible,
// Gaussian noise on forces, torques, poses and (optionally written) measured
// kinematics, at a given sample rate. Deterministic for a given seed.
//
// Built-in objects:
//   "seed-table1"  the paper's simulation object (Table I): m = 1.3 kg,
//                  c = (0.2, 0.5, 0.1) m, H_cm = (40.15, 12.92, 47.99, -12.97,
//                  -2.59, -6.49) x 1e-2 kg m^2; geometry = the uniform box with
//                  that inertia; four points of force application (a pinch
//                  with two fingertips on each of the box's two largest faces).
//   "box"          0.5 kg uniform box 0.2 x 0.1 x 0.05 m, CoM (0.02, -0.01, 0.03).
// The paper's force-noise variances: kPaperForceVariances.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/io/mesh.h"
#include "tactforce/inertia/truth.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

inline constexpr double kPaperForceVariances[] = {0.0, 0.1, 0.25, 0.5, 1.0};  // N^2

struct SinusoidComponent {
  int axis = 0;  // position: world x,y,z = 0,1,2; orientation: yaw(z), pitch(y), roll(x) = 0,1,2
  double amplitude = 0.0;  // m or rad
  double frequency_hz = 0.0;
  double phase = 0.0;  // rad
};

struct ExcitationTrajectory {
  Vec3 position_offset = Vec3::Zero();     // m (world)
  Vec3 orientation_offset = Vec3::Zero();  // yaw, pitch, roll (rad)
  std::vector<SinusoidComponent> position;
  std::vector<SinusoidComponent> orientation;

  // Two sinusoids per axis: ~0.1 m / 0.2-0.8 Hz in position, 0.2-0.8 rad in
  // orientation (pitch kept below 0.7 rad, away from gimbal lock).
  static ExcitationTrajectory Default();
  // Position, world velocity and acceleration; rotation, body angular
  // velocity and acceleration (analytic derivatives).
  void Evaluate(double t, Vec3* p, Vec3* v, Vec3* a, Eigen::Matrix3d* R, Vec3* w, Vec3* dw) const;
};

enum class SimulationMode { kWristWrench, kInHand };

// Standard deviations. The paper's noise is a force VARIANCE (N^2):
// force_sigma = sqrt(variance).
struct SimulationNoise {
  double force_sigma = 0.0;                 // N, per component (contact forces or wrench force)
  double torque_sigma = 0.0;                // N m, wrench torque (wrist mode)
  double position_sigma = 0.0;              // m
  double orientation_sigma = 0.0;           // rad (per axis, right perturbation)
  double linear_acceleration_sigma = 0.0;   // m/s^2 on written ax..az
  double angular_acceleration_sigma = 0.0;  // rad/s^2 on written dwx..dwz
  double angular_velocity_sigma = 0.0;      // rad/s on written wx..wz
};

// Nadeau et al. 2023 levels "low", "moderate", "high" (accelerations and
// wrench); InvalidArgument for other names.
absl::StatusOr<SimulationNoise> NadeauNoise(const std::string& level);

struct SimulatedObject {
  std::string name;
  InertialParameters params;
  std::vector<Vec3> hull;  // convex-hull vertices (object frame)
  // The solid whose uniform density gives `params` (the box below, or a
  // mesh given by the caller), object frame, metres, outward-facing.
  io::TriangleMesh mesh;
  std::vector<Vec3> contact_points;
  std::vector<Vec3> contact_normals;  // unit, into the object
};

std::vector<std::string> BuiltInObjectNames();
absl::StatusOr<SimulatedObject> BuiltInObject(const std::string& name);
// An object with the given parameters: geometry = the uniform box with the
// same inertia (principal axes, centred on the CoM), contacts as for
// seed-table1. InvalidArgument when the parameters are not consistent.
absl::StatusOr<SimulatedObject> ObjectFromParameters(const std::string& name,
                                                     const InertialParameters& params);

struct SimulationOptions {
  std::string object = "seed-table1";
  std::optional<SimulatedObject> custom;  // used instead of `object` when set
  SimulationMode mode = SimulationMode::kInHand;
  int num_contacts = 4;    // in-hand: 2..4 of the object's contact points
  double duration = 10.0;  // s
  double rate_hz = 100.0;
  ExcitationTrajectory trajectory = ExcitationTrajectory::Default();
  Vec3 gravity = Vec3(0, 0, -9.81);
  SimulationNoise noise;
  bool write_kinematics = false;  // emit wx..az columns (noisy if noise set)
  double friction = 1.0;          // in-hand: Coulomb mu of the fingertips
  double min_normal_force = 2.0;  // in-hand: squeeze (N)
  uint64_t seed = 1;
};

struct SimulationResult {
  InertiaSamples samples;
  InertiaTruth truth;
  SimulatedObject object;
};

// InvalidArgument naming the option ("rate_hz: must be > 0") or the step the
// planner could not solve ("in-hand forces infeasible at t = 3.21 s").
absl::StatusOr<SimulationResult> SimulateInertia(const SimulationOptions& options);

// Writes <csv_path> and <truth_path>.
absl::Status WriteSimulation(const SimulationResult& result, const std::string& csv_path,
                             const std::string& truth_path);

// Adds Gaussian noise in place to existing samples (wrench or contact forces,
// poses, measured kinematics when present) — e.g. Nadeau levels on the
// shared workshop tools.
void AddNoise(InertiaSamples& samples, const SimulationNoise& noise, uint64_t seed);

}  // namespace tactforce::inertia
