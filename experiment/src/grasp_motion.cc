// The grasp trial's clock and the hand's motion: the phase timeline, the
// minimum-jerk profiles of the lift (or the cube's pivot) and the place, and
// where that rigid motion carries a point held by the hand. Shared by the
// set-up (the planner's Newton-Euler wrench per tick) and the trial (the
// fingertip targets and the object's expected pose).
#include <algorithm>

#include "grasp_internal.h"

namespace tactforce::experiment {

using planner::Vec3;

void MinJerk(double tau, double* s, double* ds, double* dds) {
  tau = std::clamp(tau, 0.0, 1.0);
  const double t2 = tau * tau, t3 = t2 * tau;
  *s = t3 * (10 - 15 * tau + 6 * t2);
  *ds = 30 * t2 * (1 - 2 * tau + t2);
  *dds = 60 * tau - 180 * t2 + 120 * t3;
}

Timeline::Timeline(const PhaseDurations& p) {
  t_settle = p.close;
  t_hold = t_settle + p.settle;
  t_lift = t_hold + p.hold;
  t_hold_lifted = t_lift + p.lift;
  t_place = t_hold_lifted + p.hold_lifted;
  t_placed = t_place + p.place;
  t_switched = t_placed + p.placed;
  t_end = t_switched + p.switched;
  has_placed = p.placed > 0;
  has_switched = p.switched > 0;
}

Phase Timeline::At(double t) const {
  if (t < t_settle) return Phase::kClose;
  if (t < t_hold) return Phase::kSettle;
  if (t < t_lift) return Phase::kHold;
  if (t < t_hold_lifted) return Phase::kLift;
  if (t < t_place) return Phase::kHoldLifted;
  if (t < t_placed || (!has_placed && !has_switched)) return Phase::kPlace;
  if (t < t_switched || !has_switched) return Phase::kPlaced;
  return Phase::kSwitched;
}

HandMotion GraspSetup::Impl::Motion(double t) const {
  HandMotion h;
  double phi = 0, dphi = 0, ddphi = 0;
  const PhaseDurations& d = phases;
  if (t >= timeline.t_lift && t < timeline.t_hold_lifted) {
    double s, ds, dds;
    MinJerk((t - timeline.t_lift) / d.lift, &s, &ds, &dds);
    phi = s, dphi = ds / d.lift, ddphi = dds / (d.lift * d.lift);
  } else if (t >= timeline.t_hold_lifted && t < timeline.t_place) {
    phi = 1;
  } else if (t >= timeline.t_place && d.place > 0) {
    double s, ds, dds;
    MinJerk((t - timeline.t_place) / d.place, &s, &ds, &dds);
    phi = 1 - s, dphi = -ds / d.place, ddphi = -dds / (d.place * d.place);
  }
  if (pivot) {
    const double th = amplitude * phi, om = amplitude * dphi, al = amplitude * ddphi;
    h.R = Eigen::AngleAxisd(th, Vec3::UnitX()).toRotationMatrix();
    h.w = Vec3(om, 0, 0);
    h.dw = Vec3(al, 0, 0);
  } else {
    h.p = Vec3(0, 0, amplitude * phi);
    h.v = Vec3(0, 0, amplitude * dphi);
    h.a = Vec3(0, 0, amplitude * ddphi);
  }
  return h;
}

Vec3 GraspSetup::Impl::Apply(const HandMotion& h, const Vec3& x0) const {
  return h.R * (x0 - pivot_point) + pivot_point + h.p;
}

Vec3 GraspSetup::Impl::Velocity(const HandMotion& h, const Vec3& x0) const {
  return h.w.cross(h.R * (x0 - pivot_point)) + h.v;
}

Vec3 GraspSetup::Impl::Acceleration(const HandMotion& h, const Vec3& x0) const {
  const Vec3 r = h.R * (x0 - pivot_point);
  return h.dw.cross(r) + h.w.cross(h.w.cross(r)) + h.a;
}

}  // namespace tactforce::experiment
