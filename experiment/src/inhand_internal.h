// Internal (not installed): what RunInHand prepares once (object, contact
// layout, motion, per-tick force plans, MJCF) and the sensing models it logs
// through.
#pragma once

#include <array>
#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "tactforce/experiment/inhand.h"
#include "tactforce/inertia/simulate.h"

namespace tactforce::experiment::inhand_internal {

using Eigen::Matrix3d;
using Eigen::Vector3d;

inline constexpr int kFingers = 4;
inline constexpr double kRampSeconds = 1.0;  // the excitation fades in over this
inline constexpr double kRetract = 0.012;    // m a broken contact's fingertip backs off
inline constexpr double kBreakBlend = 0.05;  // s to back off / come back
// The fingertips turn with the object (as a finger's distal link turns with
// the hand's motion): a sphere that only translates cannot stay stuck to a
// rotating surface, it must slide by r times the rotation. Rotational PD
// about each fingertip's ball joint, natural frequency 300 rad/s on a
// (deliberately large) fingertip inertia so friction torques barely twist it.
inline constexpr double kFingertipInertia = 1e-4;  // kg m^2
inline constexpr double kRotationOmega = 300;      // rad/s

// The object's commanded motion at one instant: origin position (world),
// rotation, and their derivatives (world frame).
struct Motion {
  Vector3d p = Vector3d::Zero(), v = Vector3d::Zero(), a = Vector3d::Zero();
  Matrix3d R = Matrix3d::Identity();
  Vector3d w = Vector3d::Zero(), dw = Vector3d::Zero();
  // World position, velocity and acceleration of an object-frame point.
  Vector3d Point(const Vector3d& x) const { return p + R * x; }
  Vector3d PointVelocity(const Vector3d& x) const { return v + w.cross(R * x); }
  Vector3d PointAcceleration(const Vector3d& x) const {
    const Vector3d r = R * x;
    return a + dw.cross(r) + w.cross(w.cross(r));
  }
};

struct Setup {
  InHandConfig cfg;
  InHandObject object;
  inertia::InertialParameters truth;
  TactileForceModel force_model;
  std::array<Vector3d, kFingers> contact_point,
      contact_normal;  // object frame; normals into the object
  Matrix3d rest_R = Matrix3d::Identity();
  Vector3d rest_center = Vector3d(0, 0, 0.3);  // box centre, world (m)
  inertia::ExcitationTrajectory excitation;    // scaled, about the box centre
  double dt_tick = 0.005;
  std::vector<std::array<Vector3d, kFingers>>
      tick_force;  // planned, object frame; tick 0 at t = -settle
  std::string mjcf;

  // t: seconds since logging began (negative during the settle: at rest).
  Motion MotionAt(double t) const;
  // Fraction (0..1) by which contact i is backed off at t (scheduled breaks).
  double BreakBlend(int i, double t) const;
  bool InBreak(int i, double t) const;  // a break of contact i covers t (with its blend margins)
  int Tick(double t) const;             // control tick index at t (clamped)
};

absl::StatusOr<Setup> PrepareInHand(const InHandConfig& config);

// The sensing chain of one run: tactile force model per contact and the
// tracker, seeded from the run's seed.
class Sensing {
 public:
  Sensing(const Setup& setup, uint64_t seed);
  // Moves the drifting force biases on by one log interval.
  void Advance();
  // Reading of a true world force on contact i; `sigma` per component (N).
  Vector3d ReadForce(int i, const Vector3d& f_true, double* sigma);
  Vector3d ReadPoint(const Vector3d& x_true);
  // Tracked pose from the true pose and the fingertip centres (world).
  void Track(int sample, const Vector3d& p_true, const Matrix3d& R_true,
             const std::array<Vector3d, kFingers>& tips,
             const std::array<bool, kFingers>& tip_usable, Vector3d* p, Matrix3d* R, bool* dropout);

 private:
  const Setup& s_;
  std::mt19937_64 rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::array<Vector3d, kFingers> bias_;
  // Vision: the last pose and how many samples of a dropout remain.
  Vector3d last_p_ = Vector3d::Zero();
  Matrix3d last_R_ = Matrix3d::Identity();
  int dropout_left_ = 0;
  // Kinematic: the attachment at the first sample.
  bool attached_ = false;
  std::array<Vector3d, kFingers> tips0_;
  Vector3d anchor_offset_ = Vector3d::Zero();  // origin - fingertip 0 centre (world, at t0)
  Matrix3d R0_ = Matrix3d::Identity();
};

// Rotation taking the centred points `from` onto `to` (Kabsch), over the
// indices with use[i].
Matrix3d KabschRotation(const std::array<Vector3d, kFingers>& from,
                        const std::array<Vector3d, kFingers>& to,
                        const std::array<bool, kFingers>& use);

// Statistics of a finished run (everything but wall time).
void ComputeStats(const Setup& setup, InHandRun* run);

}  // namespace tactforce::experiment::inhand_internal
