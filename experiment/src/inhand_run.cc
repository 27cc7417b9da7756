// RunInHand: the MuJoCo run. Every 1 ms physics step a PD in fingertip space
// (J = I, gravity compensated, the fingertip's own acceleration fed forward)
// tracks targets carried by the commanded object motion: each fingertip's
// contact point, pressed in by K^-1 times its planned force (no force
// feedback: an admittance on the force error also integrates along the
// rigid-motion directions, where the object's dynamic lag shows, and walked
// the grasp into the friction limit). A scheduled break backs a fingertip off
// by 12 mm (50 ms blends) while the plan holds the object with the others.
// At each log instant the state is re-evaluated (mj_forward) so forces and
// accelerations belong to the logged pose; the log gets the true rows, the
// sensed samples, events, and the accumulators of the statistics.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "inhand_internal.h"
#include "scene.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace inhand_internal {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  const size_t h = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + h, v.end());
  return v[h];
}

class InHandSim {
 public:
  InHandSim(const Setup& s, Scene& sc)
      : s_(s), sc_(sc), m_(sc.m), d_(sc.d), sense_(s, s.cfg.seed * 7919 + 13) {}
  void Locate();
  absl::Status Simulate(const std::function<void(double)>& progress, InHandRun* out);
  void FinishForceStats(InHandStats* st) const;

 private:
  void ApplyForces(double t);
  void ApplyFingertipRotation(const Motion& mo);
  void Log(double t, InHandRun* out);
  void LogContacts(double t, const Vector3d& p, const Matrix3d& R, InHandTruthRow* row,
                   InHandRun* out);
  void SenseSample(double t, const InHandTruthRow& row, const std::array<Vector3d, kFingers>& fw,
                   const std::array<Vector3d, kFingers>& pw, InHandRun* out);
  void NewtonEulerResidual(const InHandTruthRow& row, InHandStats* st);

  const Setup& s_;
  Scene& sc_;
  mjModel* m_;
  mjData* d_;
  Sensing sense_;
  int obj_body_ = -1, obj_q_ = -1, obj_v_ = -1, box_ = -1;
  std::array<int, kFingers> geom_, body_, dof_, qadr_;
  std::array<Vector3d, kFingers> open_;
  std::array<Vector3d, kFingers> slip_ref_;
  std::array<bool, kFingers> was_on_{}, slip_ref_set_{};
  int samples_ = 0;
  double ne_sq_f_ = 0, ne_sq_t_ = 0;
  int ne_n_ = 0;
  std::vector<double> mag_err_, ang_err_;
  long covered_ = 0, components_ = 0;
};

void InHandSim::Locate() {
  obj_body_ = sc_.Body("object");
  const int j = sc_.Joint("object_free");
  obj_q_ = m_->jnt_qposadr[j];
  obj_v_ = m_->jnt_dofadr[j];
  box_ = sc_.Geom("box");
  for (int i = 0; i < kFingers; ++i) {
    geom_[i] = sc_.Geom(absl::StrCat("f", i, "g").c_str());
    body_[i] = sc_.Body(absl::StrCat("f", i).c_str());
    const int jx = sc_.Joint(absl::StrCat("f", i, "x").c_str());
    dof_[i] = m_->jnt_dofadr[jx];
    qadr_[i] = m_->jnt_qposadr[jx];
    open_[i] = Vector3d(m_->body_pos + 3 * body_[i]);
  }
}

// Fingertip PD and the object's external forces (support, pushes).
void InHandSim::ApplyForces(double t) {
  const Motion mo = s_.MotionAt(t);
  const std::array<Vector3d, kFingers>& plan = s_.tick_force[s_.Tick(t)];
  const InHandConfig& c = s_.cfg;
  const double kd = 2 * std::sqrt(c.kp * c.fingertip_mass);
  for (int i = 0; i < kFingers; ++i) {
    const Vector3d x0 = s_.contact_point[i] - s_.contact_normal[i] * c.fingertip_radius;
    const double b = s_.BreakBlend(i, t);
    const Vector3d press = mo.R * plan[i] / c.kp;
    const Vector3d target =
        mo.Point(x0) + (1 - b) * press - b * kRetract * (mo.R * s_.contact_normal[i]);
    const Vector3d vt = mo.PointVelocity(x0), at = mo.PointAcceleration(x0);
    for (int a = 0; a < 3; ++a) {
      const double x = open_[i](a) + d_->qpos[qadr_[i] + a];
      d_->qfrc_applied[dof_[i] + a] = c.kp * (target(a) - x) +
                                      kd * (vt(a) - d_->qvel[dof_[i] + a]) +
                                      c.fingertip_mass * (at(a) + (a == 2 ? 9.81 : 0.0));
    }
  }
  ApplyFingertipRotation(mo);
  Vector3d f(0, 0, c.support_fraction * s_.truth.mass * 9.81);
  for (const Push& p : c.pushes)
    if (t >= p.start && t < p.start + p.duration) f += p.force;
  for (int a = 0; a < 3; ++a) d_->xfrc_applied[6 * obj_body_ + a] = f(a);
}

// Each fingertip keeps its orientation relative to the commanded object
// (world-frame torque through xfrc_applied).
void InHandSim::ApplyFingertipRotation(const Motion& mo) {
  const double k = kFingertipInertia * kRotationOmega * kRotationOmega,
               kd = 2 * kFingertipInertia * kRotationOmega;
  const Matrix3d target = mo.R * s_.rest_R.transpose();
  for (int i = 0; i < kFingers; ++i) {
    const double* q = d_->qpos + qadr_[i] + 3;
    const Matrix3d R = Eigen::Quaterniond(q[0], q[1], q[2], q[3]).normalized().toRotationMatrix();
    const Eigen::AngleAxisd e(target * R.transpose());
    const Vector3d w = R * Vector3d(d_->qvel + dof_[i] + 3);
    const Vector3d tau = k * e.angle() * e.axis() + kd * (mo.w - w);
    for (int a = 0; a < 3; ++a) d_->xfrc_applied[6 * body_[i] + 3 + a] = tau(a);
  }
}

absl::Status InHandSim::Simulate(const std::function<void(double)>& progress, InHandRun* out) {
  const double dt = m_->opt.timestep;
  const InHandConfig& c = s_.cfg;
  const int n_samples = static_cast<int>(std::floor(c.duration * c.rate + 1e-9)) + 1;
  const long total = std::lround((c.settle + c.duration) / dt) + 1;
  int next = 0;
  for (long k = 0; k <= total && next < n_samples; ++k) {
    const double t = k * dt - c.settle;
    ApplyForces(t);
    if (t >= next / c.rate - 0.5 * dt) {  // the forces and accelerations this step will use
      mj_forward(m_, d_);
      Log(t, out);
      ++next;
      if (progress && next % 100 == 0) progress(static_cast<double>(next) / n_samples);
    }
    mj_step(m_, d_);
    if (!std::isfinite(d_->qpos[obj_q_])) return absl::InternalError("mujoco: simulation diverged");
  }
  return absl::OkStatus();
}

void InHandSim::Log(double t, InHandRun* out) {
  InHandTruthRow row;
  row.t = t;
  const double* q = d_->qpos + obj_q_;
  row.position = Vector3d(q[0], q[1], q[2]);
  row.orientation = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).normalized();
  LogContacts(t, row.position, row.orientation.toRotationMatrix(), &row, out);
  NewtonEulerResidual(row, &out->stats);
  out->truth_log.push_back(std::move(row));
  ++samples_;
}

void InHandSim::LogContacts(double t, const Vector3d& p, const Matrix3d& R, InHandTruthRow* row,
                            InHandRun* out) {
  std::array<Vector3d, kFingers> fw, pw;
  for (int i = 0; i < kFingers; ++i) {
    double f[3], pt[3];
    const bool on = PairForce(m_, d_, box_, geom_[i], f, pt) > 0 && Vector3d(f).norm() > 1e-6;
    fw[i] = on ? Vector3d(f) : Vector3d::Zero();
    pw[i] = on ? Vector3d(pt) : Vector3d(p + R * s_.contact_point[i]);
    const Vector3d po = R.transpose() * (pw[i] - p);
    if (on && !slip_ref_set_[i]) slip_ref_[i] = po, slip_ref_set_[i] = true;
    if (samples_ > 0 && on != was_on_[i]) {
      const bool scheduled = s_.InBreak(i, t) || s_.InBreak(i, t - kBreakBlend);
      out->events.push_back({t, on ? "contact_made" : "contact_lost", i,
                             scheduled ? "scheduled break" : "unscheduled"});
      if (!on && !scheduled) ++out->stats.contact_losses;
    }
    was_on_[i] = on;
    row->force.push_back(R.transpose() * fw[i]);
    row->point.push_back(on ? po : s_.contact_point[i]);
    row->slip_mm.push_back(on ? 1e3 * (po - slip_ref_[i]).norm() : 0.0);
    row->in_contact.push_back(on);
  }
  SenseSample(t, *row, fw, pw, out);
}

// The logged sample: tracked pose, sensed forces and points in the tracked frame.
void InHandSim::SenseSample(double t, const InHandTruthRow& row,
                            const std::array<Vector3d, kFingers>& fw,
                            const std::array<Vector3d, kFingers>& pw, InHandRun* out) {
  sense_.Advance();
  std::array<Vector3d, kFingers> tips;
  std::array<bool, kFingers> usable;
  for (int i = 0; i < kFingers; ++i) {
    tips[i] = Vector3d(d_->xpos + 3 * body_[i]);
    usable[i] = !s_.InBreak(i, t) && s_.BreakBlend(i, t) == 0;
  }
  Vector3d p;
  Matrix3d R;
  bool dropout = false;
  sense_.Track(samples_, row.position, row.orientation.toRotationMatrix(), tips, usable, &p, &R,
               &dropout);
  if (dropout) out->events.push_back({t, "tracker_dropout", -1, ""}), ++out->stats.tracker_dropouts;
  out->tracker_error.push_back(p - row.position);
  inertia::InertiaSample x;
  x.t = t;
  x.position = p;
  x.orientation = Eigen::Quaterniond(R).normalized();
  const TactileForceModel& fm = s_.force_model;
  for (int i = 0; i < kFingers; ++i) {
    inertia::ContactReading c;
    if (row.in_contact[i]) {
      const Vector3d f = sense_.ReadForce(i, fw[i], &c.sigma);
      c.force = R.transpose() * f;
      c.point = R.transpose() * (sense_.ReadPoint(pw[i]) - p);
      const Vector3d e = f - fw[i];
      for (int a = 0; a < 3; ++a) covered_ += std::abs(e(a)) <= c.sigma, ++components_;
      mag_err_.push_back(std::abs(f.norm() - fw[i].norm()));
      const double cosang = f.dot(fw[i]) / std::max(1e-12, f.norm() * fw[i].norm());
      ang_err_.push_back(std::acos(std::clamp(cosang, -1.0, 1.0)) * 180 / M_PI);
    } else {
      c.point = s_.contact_point[i];
      c.sigma = s_.cfg.ideal_forces ? 0 : std::hypot(fm.bias_sigma, fm.noise_floor);
    }
    x.contacts.push_back(c);
  }
  out->samples.samples.push_back(std::move(x));
}

// Logged true forces (+ the support) against the truth's Newton-Euler
// wrench with MuJoCo's accelerations (free joint: linear part of the origin
// in the world, angular part in the body frame).
void InHandSim::NewtonEulerResidual(const InHandTruthRow& row, InHandStats* st) {
  const Matrix3d R = row.orientation.toRotationMatrix();
  planner::TrajectoryStep step;
  step.gravity = R.transpose() * Vector3d(0, 0, -9.81);
  step.linear_acceleration = R.transpose() * Vector3d(d_->qacc + obj_v_);
  step.angular_velocity = Vector3d(d_->qvel + obj_v_ + 3);
  step.angular_acceleration = Vector3d(d_->qacc + obj_v_ + 3);
  planner::ObjectModel om;
  om.mass = s_.truth.mass;
  om.com = s_.truth.com;
  const planner::Wrench need =
      planner::RequiredContactWrench(om, s_.truth.inertia_com.Matrix(), step);
  const Vector3d support =
      R.transpose() * Vector3d(0, 0, s_.cfg.support_fraction * s_.truth.mass * 9.81);
  Vector3d f = support, tq = s_.truth.com.cross(support);
  for (int i = 0; i < kFingers; ++i) f += row.force[i], tq += row.point[i].cross(row.force[i]);
  bool pushed = false;
  for (const Push& p : s_.cfg.pushes)
    pushed = pushed || (row.t >= p.start && row.t < p.start + p.duration);
  if (pushed) return;  // the push is an unlogged external force by design
  const double ef = (f - need.force).norm(), et = (tq - need.torque).norm();
  st->ne_residual_force_max = std::max(st->ne_residual_force_max, ef);
  ne_sq_f_ += ef * ef, ne_sq_t_ += et * et, ++ne_n_;
  st->ne_residual_force_rms = std::sqrt(ne_sq_f_ / ne_n_);
  st->ne_residual_torque_rms = std::sqrt(ne_sq_t_ / ne_n_);
}

void InHandSim::FinishForceStats(InHandStats* st) const {
  st->median_magnitude_error = Median(mag_err_);
  st->median_angle_error_deg = Median(ang_err_);
  st->sigma_coverage = components_ > 0 ? static_cast<double>(covered_) / components_ : 0;
}

}  // namespace
}  // namespace inhand_internal

absl::StatusOr<InHandRun> RunInHand(const InHandConfig& config,
                                    const std::function<void(double)>& progress) {
  using namespace inhand_internal;  // NOLINT: the run's internals
  const auto wall0 = std::chrono::steady_clock::now();
  TF_ASSIGN_OR_RETURN(Setup setup, PrepareInHand(config));
  TF_ASSIGN_OR_RETURN(auto scene, Scene::FromMjcf(setup.mjcf));
  InHandRun run;
  run.object = setup.object;
  run.object_name = setup.object.name;
  run.truth = setup.truth;
  run.mesh = std::make_shared<const io::TriangleMesh>(InHandObjectMesh(setup.object));
  run.hull = run.mesh->vertices;
  run.samples.source = inertia::ForceSource::kContacts;
  run.samples.num_contacts = kFingers;
  run.samples.source_name = absl::StrCat("inhand ", run.object_name);
  InHandSim sim(setup, *scene);
  sim.Locate();
  TF_RETURN_IF_ERROR(sim.Simulate(progress, &run));
  sim.FinishForceStats(&run.stats);
  if (!config.ideal_tracking && config.tracker == Tracker::kVision) {
    run.tracker_position_sigma = config.vision.position_sigma;
    run.tracker_orientation_sigma = config.vision.orientation_sigma_deg * M_PI / 180;
  }
  ComputeStats(setup, &run);
  run.stats.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (progress) progress(1.0);
  return run;
}

}  // namespace tactforce::experiment
