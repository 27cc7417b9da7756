// One in-grasp probe trial in MuJoCo (SimulateProbe, probe_internal.h). Every
// 1 ms step: the holding fingertips' PD (J = I) tracks targets offset from
// their contacts by the planned force over the stiffness; the probe
// fingertip is force controlled (the planned probe force turned into the
// world by the tracked object pose, gravity compensated). Every sample
// (sample_rate, 200 Hz): the probe's contact force through the 3-axis
// tactile model (a per-trial bias and per-sample noise on each fingertip
// axis) and its contact point, both expressed in the object frame through
// the tracked pose; the holding fingertips' sensed forces drive the
// admittance of `experiment grasp` towards the plan. Phases: close (object
// held kinematically), settle (object released, probe force ramps in), probe.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "probe_internal.h"
#include "scene.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

using Eigen::Matrix3d;
using planner::Vec3;

constexpr double kMaxTargetStep = 0.001;  // m per tick, as in the grasp experiment
constexpr double kDropDistance = 0.02;    // m

struct Tip {
  int geom = -1, dof = -1, qadr = -1;
  Vec3 start;           // world position of the body at qpos 0
  Vec3 contact_center;  // centre touching its contact at rest (world)
  Vec3 offset;          // target - contact_center (world, m)
  Vec3 bias;            // tactile bias (N, fingertip = world axes)
};

class ProbeRun {
 public:
  ProbeRun(const ProbeConfig& c, const ProbeSetup& s, Scene& sc, std::mt19937_64& rng)
      : c_(c), s_(s), sc_(sc), m_(sc.m), d_(sc.d), rng_(rng), noise_(0.0, 1.0) {
    kd_ = 2 * std::sqrt(c.kp * c.fingertip_mass);
    rate_ = c.slope.sample_rate;
    t0_ = kCloseTime + kSettleTime;
    rec_.trial.name = "in-grasp probe";
  }
  void Locate();
  absl::StatusOr<ProbeRecording> Run();

 private:
  Vec3 Position() const {
    return Vec3(d_->qpos[obj_q_], d_->qpos[obj_q_ + 1], d_->qpos[obj_q_ + 2]);
  }
  Matrix3d Rotation() const {
    const double* q = d_->qpos + obj_q_ + 3;
    return Eigen::Quaterniond(q[0], q[1], q[2], q[3]).toRotationMatrix();
  }
  Vec3 Sense(const Vec3& truth, const Vec3& bias) {
    return truth + bias + c_.force_sigma * Vec3(noise_(rng_), noise_(rng_), noise_(rng_));
  }
  Vec3 TipPos(const Tip& f) const {
    return f.start + Vec3(d_->qpos[f.qadr], d_->qpos[f.qadr + 1], d_->qpos[f.qadr + 2]);
  }
  int Sample(double t) const;
  void HoldObjectAtRest();
  void ApplyHolding(double t);
  void ApplyProbe(double t);
  void Tick(double t);
  void RecordProbe(double t);
  void Admit(int k);

  const ProbeConfig& c_;
  const ProbeSetup& s_;
  Scene& sc_;
  mjModel* m_;
  mjData* d_;
  std::mt19937_64& rng_;
  std::normal_distribution<double> noise_;
  std::vector<Tip> tips_;  // holding fingertips, then the probe
  int box_ = -1, obj_q_ = -1, obj_v_ = -1;
  double kd_ = 0, rate_ = 200, t0_ = 0;
  Vec3 x0_ = Vec3::Zero(), probe0_ = Vec3::Zero();
  Matrix3d R0_ = Matrix3d::Identity();
  double stop_at_ = -1;
  bool started_ = false;
  ProbeRecording rec_;
};

void ProbeRun::Locate() {
  box_ = sc_.Geom("box");
  const int j = sc_.Joint("object_free");
  obj_q_ = m_->jnt_qposadr[j];
  obj_v_ = m_->jnt_dofadr[j];
  std::normal_distribution<double> bias(0.0, c_.force_bias);
  for (int i = 0; i <= kHoldingFingers; ++i) {
    const std::string name = i < kHoldingFingers ? absl::StrCat("f", i) : std::string("p");
    Tip f;
    f.geom = sc_.Geom((name + "g").c_str());
    const int jx = sc_.Joint((name + "x").c_str());
    f.dof = m_->jnt_dofadr[jx];
    f.qadr = m_->jnt_qposadr[jx];
    const int body = sc_.Body(name.c_str());
    f.start = Vec3(m_->body_pos[3 * body], m_->body_pos[3 * body + 1], m_->body_pos[3 * body + 2]);
    if (i < kHoldingFingers) {
      const planner::Contact& k = s_.holding[i];
      f.contact_center = s_.rest_position + k.position - k.normal * c_.fingertip_radius;
      f.offset = c_.hold_scale * s_.plan.holding.steps[0].forces[i] / c_.kp;
    } else {
      f.contact_center = f.start;
      f.offset = Vec3::Zero();
    }
    f.bias = Vec3(bias(rng_), bias(rng_), bias(rng_));
    tips_.push_back(f);
  }
}

int ProbeRun::Sample(double t) const {
  const int n = static_cast<int>(s_.plan.times.size());
  return std::clamp(static_cast<int>(std::floor((t - t0_) * rate_ + 1e-9)), 0, n - 1);
}

// Close: the hand takes the object (its pose is held until the fingertips are on it).
void ProbeRun::HoldObjectAtRest() {
  for (int a = 0; a < 3; ++a) d_->qpos[obj_q_ + a] = s_.rest_position[a];
  d_->qpos[obj_q_ + 3] = 1;
  for (int a = 4; a < 7; ++a) d_->qpos[obj_q_ + a] = 0;
  for (int a = 0; a < 6; ++a) d_->qvel[obj_v_ + a] = 0;
}

// Holding fingertips: a minimum-jerk close onto the targets, then PD on them.
void ProbeRun::ApplyHolding(double t) {
  for (int i = 0; i < kHoldingFingers; ++i) {
    const Tip& f = tips_[i];
    const Vec3 goal = f.contact_center + f.offset;
    Vec3 target = goal, vtarget = Vec3::Zero();
    if (t < kCloseTime) {
      const double tau = t / kCloseTime;
      const double s = tau * tau * tau * (10 - 15 * tau + 6 * tau * tau);
      const double ds = 30 * tau * tau * (1 - tau) * (1 - tau) / kCloseTime;
      target = f.start + s * (goal - f.start);
      vtarget = ds * (goal - f.start);
    }
    const Vec3 x = TipPos(f);
    for (int a = 0; a < 3; ++a)
      d_->qfrc_applied[f.dof + a] = c_.kp * (target[a] - x[a]) +
                                    kd_ * (vtarget[a] - d_->qvel[f.dof + a]) +
                                    (a == 2 ? c_.fingertip_mass * 9.81 : 0.0);
  }
}

// Probe fingertip: at rest while the hand closes, then the planned force
// (ramped in over the settle) along the tracked object's axes.
void ProbeRun::ApplyProbe(double t) {
  const Tip& p = tips_[kHoldingFingers];
  Vec3 force = Vec3::Zero();
  if (t < kCloseTime) {
    const Vec3 x = TipPos(p);
    for (int a = 0; a < 3; ++a) force[a] = c_.kp * (p.start[a] - x[a]) - kd_ * d_->qvel[p.dof + a];
  } else {
    const double ramp = std::min(1.0, (t - kCloseTime) / kSettleTime);
    force = ramp * (Rotation() * s_.plan.probe_forces[t < t0_ ? 0 : Sample(t)]);
  }
  for (int a = 0; a < 3; ++a)
    d_->qfrc_applied[p.dof + a] = force[a] + (a == 2 ? c_.fingertip_mass * 9.81 : 0.0);
}

// The probe's sensed force and contact point (object frame), the object's
// motion since the probe began, and the stop rule.
void ProbeRun::RecordProbe(double t) {
  const Matrix3d R = Rotation();
  const Vec3 x = Position();
  const Tip& p = tips_[kHoldingFingers];
  double f[3], pt[3];
  if (PairForce(m_, d_, box_, p.geom, f, pt) == 0) return;
  estimator::FrictionSample smp;
  smp.t = t - t0_;
  smp.force = R.transpose() * Sense(Vec3(f[0], f[1], f[2]), p.bias);
  smp.contact_point = R.transpose() * (Vec3(pt[0], pt[1], pt[2]) - x) +
                      c_.contact_sigma * Vec3(noise_(rng_), noise_(rng_), noise_(rng_));
  rec_.trial.samples.push_back(smp);
  const double c = std::clamp(((R * R0_.transpose()).trace() - 1) / 2, -1.0, 1.0);
  rec_.motion.push_back((x - x0_).norm());
  rec_.rotation.push_back(std::acos(c) * 180 / std::numbers::pi);
  const Vec3 travel = R.transpose() * (TipPos(p) - x) - probe0_;
  if (stop_at_ < 0 && std::hypot(travel.x(), travel.y()) > c_.probe_travel_stop)
    stop_at_ = t + 0.05;
}

// Holding admittance (3D, as `experiment grasp --admittance full`) on the
// sensed holding forces towards the scaled plan of sample k.
void ProbeRun::Admit(int k) {
  const Matrix3d R = Rotation();
  for (int i = 0; i < kHoldingFingers; ++i) {
    Tip& f = tips_[i];
    double fw[3], pt[3];
    PairForce(m_, d_, box_, f.geom, fw, pt);
    const Vec3 sensed = Sense(Vec3(fw[0], fw[1], fw[2]), f.bias);
    const Vec3 desired = R * (c_.hold_scale * s_.plan.holding.steps[k].forces[i]);
    Vec3 step = c_.admittance_gain * (desired - sensed) / c_.kp;
    if (step.norm() > kMaxTargetStep) step *= kMaxTargetStep / step.norm();
    f.offset += step;
    if (f.offset.norm() > 0.03) f.offset *= 0.03 / f.offset.norm();
  }
}

void ProbeRun::Tick(double t) {
  if (!started_) {
    started_ = true;
    x0_ = Position();
    R0_ = Rotation();
    probe0_ = R0_.transpose() * (TipPos(tips_[kHoldingFingers]) - x0_);
  }
  RecordProbe(t);
  Admit(Sample(t));
}

absl::StatusOr<ProbeRecording> ProbeRun::Run() {
  const double dt = m_->opt.timestep;
  const int every = std::max(1, static_cast<int>(std::lround(1.0 / (rate_ * dt))));
  const int first_tick = static_cast<int>(std::lround(t0_ / dt));
  const double t_end = t0_ + s_.plan.times.back() + 0.2;
  for (int step = 0;; ++step) {
    const double t = step * dt;
    if (t > t_end || (stop_at_ >= 0 && t > stop_at_)) break;
    if (t < kCloseTime) HoldObjectAtRest();
    if (step >= first_tick && (step - first_tick) % every == 0) Tick(t);
    ApplyHolding(t);
    ApplyProbe(t);
    mj_step(m_, d_);
    if (!std::isfinite(d_->qpos[obj_q_])) return absl::InternalError("mujoco: simulation diverged");
    if ((Position() - s_.rest_position).norm() > kDropDistance) {
      rec_.dropped = true;
      break;
    }
  }
  return std::move(rec_);
}

}  // namespace

absl::StatusOr<ProbeRecording> SimulateProbe(const ProbeConfig& c, const ProbeSetup& setup,
                                             std::mt19937_64& rng) {
  TF_ASSIGN_OR_RETURN(std::unique_ptr<Scene> scene, Scene::FromMjcf(setup.mjcf));
  ProbeRun run(c, setup, *scene, rng);
  run.Locate();
  return run.Run();
}

}  // namespace tactforce::experiment
