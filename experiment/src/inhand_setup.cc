// PrepareInHand: the object and its four-fingertip pinch (two fingertips on
// each of the box's two largest faces, spread along its longest edge), the
// rest pose (pinch axis horizontal), the excitation (the inertia library's
// default trajectory scaled to a hand's workspace, about the box centre,
// faded in over the first second), one warm-started PlanTrajectory step per
// control tick, and the MJCF scene (free object, floating fingertip spheres
// on slide joints, explicit contact pairs).
#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "grasp_internal.h"
#include "inhand_internal.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment::inhand_internal {
namespace {

constexpr double kDiffStep = 1e-3;  // s, central differences of the commanded pose

std::string V3(const Vector3d& v) { return absl::StrFormat("%.9g %.9g %.9g", v.x(), v.y(), v.z()); }

Vector3d Vee(const Matrix3d& dR) {
  const Eigen::AngleAxisd aa(dR);
  return aa.angle() * aa.axis();
}

// Contact layout and rest orientation from the box's edges.
void LayOutContacts(Setup* s) {
  const Vector3d& d = s->object.dimensions;
  int thin = 0, lng = 0;
  for (int k = 1; k < 3; ++k) {
    if (d(k) < d(thin)) thin = k;
    if (d(k) > d(lng)) lng = k;
  }
  if (thin == lng) lng = (thin + 1) % 3;
  const int mid = 3 - thin - lng;
  const Vector3d e_thin = Vector3d::Unit(thin), e_long = Vector3d::Unit(lng),
                 e_mid = Vector3d::Unit(mid);
  const double spread = 0.35 * d(lng);
  const std::pair<int, int> pattern[kFingers] = {{+1, +1}, {-1, -1}, {-1, +1}, {+1, -1}};
  for (int i = 0; i < kFingers; ++i) {
    const auto [side, along] = pattern[i];
    s->contact_point[i] =
        s->object.center + side * 0.5 * d(thin) * e_thin + along * spread * e_long;
    s->contact_normal[i] = -side * e_thin;
  }
  // Pinch axis along world x, long edge along world y.
  Matrix3d R = Vector3d::UnitX() * e_thin.transpose() + Vector3d::UnitY() * e_long.transpose() +
               Vector3d::UnitZ() * e_mid.transpose();
  if (R.determinant() < 0) R.row(2) *= -1;
  s->rest_R = R;
}

inertia::ExcitationTrajectory ScaledExcitation(const InHandConfig& c) {
  inertia::ExcitationTrajectory e = inertia::ExcitationTrajectory::Default();
  for (auto& x : e.position) x.amplitude *= c.position_scale;
  for (auto& x : e.orientation) x.amplitude *= c.orientation_scale;
  return e;
}

// Box centre and rotation commanded at t.
void CenterPose(const Setup& s, double t, Vector3d* c, Matrix3d* R) {
  double e = 0, de, dde;
  MinJerk(t / kRampSeconds, &e, &de, &dde);
  Vector3d x;
  Matrix3d Rx;
  s.excitation.Evaluate(std::max(t, 0.0), &x, nullptr, nullptr, &Rx, nullptr, nullptr);
  const Eigen::AngleAxisd aa(Rx);
  *c = s.rest_center + e * x;
  *R = Eigen::AngleAxisd(e * aa.angle(), aa.axis()).toRotationMatrix() * s.rest_R;
}

void OriginPose(const Setup& s, double t, Vector3d* p, Matrix3d* R) {
  Vector3d c;
  CenterPose(s, t, &c, R);
  *p = c - *R * s.object.center;
}

Vector3d AngularVelocity(const Setup& s, double t) {
  Vector3d p;
  Matrix3d Rp, Rm;
  OriginPose(s, t + kDiffStep, &p, &Rp);
  OriginPose(s, t - kDiffStep, &p, &Rm);
  return Vee(Rp * Rm.transpose()) / (2 * kDiffStep);
}

// The plan problem: object, contacts, inertia; one step per control tick.
planner::TrajectoryProblem TickProblem(const Setup& s, int ticks) {
  planner::TrajectoryProblem traj;
  traj.base.object.mass = s.truth.mass;
  traj.base.object.com = s.truth.com;
  for (int i = 0; i < kFingers; ++i) {
    planner::Contact c;
    c.name = absl::StrCat("c", i);
    c.position = s.contact_point[i];
    c.normal = s.contact_normal[i];
    c.friction = s.cfg.plan_friction;
    c.min_normal_force = s.cfg.min_normal_force;
    traj.base.contacts.push_back(c);
  }
  const inertia::InertiaTensor& I = s.truth.inertia_com;
  traj.inertia = planner::Inertia{I.ixx, I.iyy, I.izz, I.ixy, I.ixz, I.iyz};
  const Vector3d support(0, 0, s.cfg.support_fraction * s.truth.mass * 9.81);
  for (int j = 0; j < ticks; ++j) {
    const double t = j * s.dt_tick - s.cfg.settle;
    const Motion m = s.MotionAt(t);
    const Matrix3d Rt = m.R.transpose();
    planner::TrajectoryStep step;
    step.gravity = Rt * Vector3d(0, 0, -9.81);
    step.linear_acceleration = Rt * m.a;
    step.angular_velocity = Rt * m.w;
    step.angular_acceleration = Rt * m.dw;
    step.external_wrench.force = Rt * support;
    step.external_wrench.torque = s.truth.com.cross(step.external_wrench.force);
    std::vector<planner::Contact> contacts;
    for (int i = 0; i < kFingers; ++i)
      if (!s.InBreak(i, t)) contacts.push_back(traj.base.contacts[i]);
    if (contacts.size() < kFingers) step.contacts = contacts;
    traj.steps.push_back(step);
  }
  return traj;
}

absl::Status PlanTicks(Setup* s) {
  s->dt_tick = 1.0 / s->cfg.control_rate;
  const int ticks = static_cast<int>(std::ceil((s->cfg.settle + s->cfg.duration) / s->dt_tick)) + 2;
  const planner::TrajectoryProblem traj = TickProblem(*s, ticks);
  auto planned =
      planner::PlanTrajectory(traj, planner::PlanOptions{}, planner::SolverKind::kGeometric, true);
  if (!planned.ok())
    return io::PrependPath(absl::InternalError(planned.status().message()), "planner");
  for (int j = 0; j < ticks; ++j) {
    const planner::PlanResult& r = planned->steps[j];
    const double t = j * s->dt_tick - s->cfg.settle;
    if (r.status != planner::PlanStatus::kOptimal)
      return absl::FailedPreconditionError(
          absl::StrFormat("planner: no holding forces at t = %.3f s (%s): lower "
                          "position_scale/orientation_scale or raise "
                          "friction",
                          t, r.message));
    std::array<Vector3d, kFingers> f;
    for (int i = 0, k = 0; i < kFingers; ++i)
      f[i] = s->InBreak(i, t) ? Vector3d::Zero() : r.forces[k++];
    s->tick_force.push_back(f);
  }
  return absl::OkStatus();
}

std::string InHandMjcf(const Setup& s) {
  const InHandConfig& c = s.cfg;
  const Motion m0 = s.MotionAt(-c.settle);
  const Eigen::Quaterniond q(m0.R);
  const inertia::InertiaTensor& I = s.truth.inertia_com;
  std::string x =
      absl::StrCat("<mujoco model=\"tactforce_inhand\">\n", OptionMjcf(c.physics), "<worldbody>\n");
  absl::StrAppend(&x, absl::StrFormat("<body name=\"object\" pos=\"%s\" quat=\"%.12g %.12g %.12g "
                                      "%.12g\">\n<joint name=\"object_free\" "
                                      "type=\"free\"/>\n<inertial pos=\"%s\" mass=\"%.12g\" "
                                      "fullinertia=\"%.12g %.12g %.12g %.12g %.12g %.12g\"/>\n"
                                      "<geom name=\"box\" type=\"box\" pos=\"%s\" size=\"%s\" "
                                      "contype=\"0\" conaffinity=\"0\" mass=\"0\"/>\n"
                                      "</body>\n",
                                      V3(m0.p), q.w(), q.x(), q.y(), q.z(), V3(s.truth.com),
                                      s.truth.mass, I.ixx, I.iyy, I.izz, I.ixy, I.ixz, I.iyz,
                                      V3(s.object.center), V3(0.5 * s.object.dimensions)));
  for (int i = 0; i < kFingers; ++i) {
    const Vector3d n = m0.R * s.contact_normal[i];
    const Vector3d center = m0.Point(s.contact_point[i]) - n * c.fingertip_radius;
    absl::StrAppend(&x,
                    absl::StrFormat("<body name=\"f%d\" pos=\"%s\">\n<joint name=\"f%dx\" "
                                    "type=\"slide\" axis=\"1 0 0\"/><joint name=\"f%dy\" "
                                    "type=\"slide\" axis=\"0 1 0\"/><joint name=\"f%dz\" "
                                    "type=\"slide\" axis=\"0 0 1\"/><joint "
                                    "name=\"f%dr\" type=\"ball\"/>\n<inertial pos=\"0 0 0\" "
                                    "mass=\"%.9g\" diaginertia=\"%.9g %.9g %.9g\"/>\n"
                                    "<geom name=\"f%dg\" type=\"sphere\" size=\"%.9g\" "
                                    "contype=\"0\" conaffinity=\"0\"/>\n</body>\n",
                                    i, V3(center), i, i, i, i, c.fingertip_mass, kFingertipInertia,
                                    kFingertipInertia, kFingertipInertia, i, c.fingertip_radius));
  }
  absl::StrAppend(&x, "</worldbody>\n<contact>\n");
  for (int i = 0; i < kFingers; ++i)
    absl::StrAppend(&x, absl::StrFormat("<pair geom1=\"f%dg\" geom2=\"box\" condim=\"%d\" "
                                        "friction=\"%.9g %.9g %.9g 0.0001 0.0001\" %s/>\n",
                                        i, c.physics.condim_fingertip, c.friction, c.friction,
                                        c.physics.torsional_friction, SolrefAttr(c.physics)));
  absl::StrAppend(&x, "</contact>\n</mujoco>\n");
  return x;
}

}  // namespace

Motion Setup::MotionAt(double t) const {
  Motion m;
  Vector3d pp, pm;
  Matrix3d Rp, Rm;
  OriginPose(*this, t, &m.p, &m.R);
  OriginPose(*this, t + kDiffStep, &pp, &Rp);
  OriginPose(*this, t - kDiffStep, &pm, &Rm);
  m.v = (pp - pm) / (2 * kDiffStep);
  m.a = (pp - 2 * m.p + pm) / (kDiffStep * kDiffStep);
  m.w = Vee(Rp * Rm.transpose()) / (2 * kDiffStep);
  m.dw = (AngularVelocity(*this, t + kDiffStep) - AngularVelocity(*this, t - kDiffStep)) /
         (2 * kDiffStep);
  return m;
}

double Setup::BreakBlend(int i, double t) const {
  double b = 0;
  for (const ContactBreak& br : cfg.breaks) {
    if (br.contact != i) continue;
    const double up = std::clamp((t - br.start) / kBreakBlend, 0.0, 1.0);
    const double down = std::clamp((br.start + br.duration - t) / kBreakBlend, 0.0, 1.0);
    b = std::max(b, std::min(up, down));
  }
  return b;
}

bool Setup::InBreak(int i, double t) const {
  for (const ContactBreak& br : cfg.breaks)
    if (br.contact == i && t >= br.start && t <= br.start + br.duration + kBreakBlend) return true;
  return false;
}

int Setup::Tick(double t) const {
  const int j = static_cast<int>(std::lround((t + cfg.settle) / dt_tick));
  return std::clamp(j, 0, static_cast<int>(tick_force.size()) - 1);
}

absl::StatusOr<Setup> PrepareInHand(const InHandConfig& config) {
  TF_RETURN_IF_ERROR(ValidateInHandConfig(config));
  Setup s;
  s.cfg = config;
  if (config.custom) {
    s.object = *config.custom;
  } else {
    TF_ASSIGN_OR_RETURN(s.object, BuiltInInHandObject(config.object));
  }
  if (s.object.name.empty()) s.object.name = config.object;
  s.truth = InHandObjectInertia(s.object);
  TF_ASSIGN_OR_RETURN(s.force_model,
                      config.custom_force_model
                          ? absl::StatusOr<TactileForceModel>(*config.custom_force_model)
                          : NamedForceModel(config.force_model));
  LayOutContacts(&s);
  s.excitation = ScaledExcitation(config);
  TF_RETURN_IF_ERROR(PlanTicks(&s));
  s.mjcf = InHandMjcf(s);
  return s;
}

}  // namespace tactforce::experiment::inhand_internal
