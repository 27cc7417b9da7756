// Inertial parameters of a rigid object and the samples they are fitted to.
//
// Conventions (identical to the inertia CSV, see samples.h):
//   * object pose in the world: position p (m) and unit quaternion q that
//     rotates OBJECT-frame vectors into the WORLD frame (R = R(q));
//   * every inertial quantity lives in the OBJECT frame: CoM c (m), inertia
//     about the CoM H_c (kg m^2) as the tensor entries
//     [[Ixx, Ixy, Ixz], [Ixy, Iyy, Iyz], [Ixz, Iyz, Izz]];
//   * wrenches and contact forces are those APPLIED TO THE OBJECT, in the
//     object frame, torques about the object origin.
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tactforce::inertia {

using Vec3 = Eigen::Vector3d;
using Vector10d = Eigen::Matrix<double, 10, 1>;

// Inertia tensor entries in the order Ixx, Iyy, Izz, Ixy, Ixz, Iyz.
struct InertiaTensor {
  double ixx = 0, iyy = 0, izz = 0, ixy = 0, ixz = 0, iyz = 0;

  Eigen::Matrix3d Matrix() const;
  static InertiaTensor FromMatrix(const Eigen::Matrix3d& m);  // symmetrised
  std::array<double, 6> ToArray() const { return {ixx, iyy, izz, ixy, ixz, iyz}; }
  static InertiaTensor FromArray(const std::array<double, 6>& a);
};

// Mass, CoM and inertia ABOUT THE COM, object frame.
struct InertialParameters {
  double mass = 0.0;
  Vec3 com = Vec3::Zero();
  InertiaTensor inertia_com;

  // Inertia about the object origin (parallel-axis theorem).
  Eigen::Matrix3d InertiaOrigin() const;
  // The 10 standard (Atkeson) parameters, linear in the Newton-Euler
  // equations: [m, m cx, m cy, m cz, Ixx, Iyy, Izz, Ixy, Ixz, Iyz] with the
  // inertia taken about the OBJECT ORIGIN.
  Vector10d ToStandard() const;
  // Inverse of ToStandard; the CoM is 0 when m == 0.
  static InertialParameters FromStandard(const Vector10d& pi);
};

// Names of the standard parameters, in ToStandard() order:
// "m", "m*cx", "m*cy", "m*cz", "Ixx", "Iyy", "Izz", "Ixy", "Ixz", "Iyz"
// (inertia about the object origin).
const std::array<const char*, 10>& StandardParameterNames();

// ---------------------------------------------------------------- samples

// Measured kinematics (optional; used instead of differentiating poses).
struct MeasuredKinematics {
  Vec3 angular_velocity = Vec3::Zero();      // w, object frame (rad/s)
  Vec3 velocity = Vec3::Zero();              // v of the origin, world (m/s)
  Vec3 angular_acceleration = Vec3::Zero();  // dw, object frame (rad/s^2)
  Vec3 acceleration = Vec3::Zero();          // a of the origin, world, without gravity (m/s^2)
};

struct ContactReading {
  Vec3 point = Vec3::Zero();  // object frame (m)
  Vec3 force = Vec3::Zero();  // applied to the object, object frame (N); zero = broken contact
  double sigma = 0.0;         // optional per-sample force std. dev. per component (N); 0 = unset
};

struct InertiaSample {
  double t = 0.0;  // s
  Vec3 position = Vec3::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
  // Wrench source (InertiaSamples::source == kWrench).
  Vec3 force = Vec3::Zero();   // N
  Vec3 torque = Vec3::Zero();  // N m about the object origin
  double force_sigma = 0.0;    // optional per-sample wrench sigmas (N, N m); 0 = unset
  double torque_sigma = 0.0;
  // Contact source (source == kContacts): exactly num_contacts entries.
  std::vector<ContactReading> contacts;
  std::optional<MeasuredKinematics> kinematics;  // all samples or none
};

enum class ForceSource { kWrench, kContacts };

struct InertiaSamples {
  ForceSource source = ForceSource::kWrench;
  int num_contacts = 0;  // kContacts only
  std::vector<InertiaSample> samples;
  // Where the samples came from, for messages: a file name and, per sample,
  // its 1-based line (CSV). Empty line_numbers: messages say "samples[i]".
  std::string source_name;
  std::vector<int> line_numbers;

  bool HasKinematics() const { return !samples.empty() && samples.front().kinematics.has_value(); }
};

}  // namespace tactforce::inertia
