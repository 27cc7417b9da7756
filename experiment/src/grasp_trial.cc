// One closed-loop grasp trial in MuJoCo and batches of them. A trial draws
// its sensors from (seed, trial) — the same draws for raw and estimated
// feedback — then steps the physics at 1 ms; every control tick it reads the
// fingertips' true contact forces through their sensor channels, estimates
// the forces (or takes the raw readings), moves the fingertip targets by the
// admittance law and scores the object's pose against where the hand's
// motion puts it; every physics step a PD in fingertip space tracks the
// targets. The steps below are the methods of `TrialRun`, in that order.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "grasp_internal.h"
#include "scene.h"

namespace tactforce::experiment {
namespace {

using planner::Vec3;
using Eigen::Matrix3d;

constexpr double kMaxTargetStep = 0.001;  // m per tick the admittance may move a target
constexpr double kOpenGap = 0.015;        // m between a fingertip and its contact when open

uint64_t SplitMix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

struct FingerContact {
  double normal = 0, shear = 0;  // N (contact-frame magnitudes, summed)
};

// The contact force the object exerts on one fingertip geom, summed over
// their active contacts.
FingerContact MeasureFinger(const mjModel* m, const mjData* d, int finger_geom, int object_body) {
  FingerContact out;
  double tx = 0, ty = 0, tz = 0;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    int other;
    if (c.geom1 == finger_geom) other = c.geom2;
    else if (c.geom2 == finger_geom) other = c.geom1;
    else continue;
    if (m->geom_bodyid[other] != object_body || c.efc_address < 0) continue;
    mjtNum f[6];
    mj_contactForce(m, d, i, f);
    out.normal += f[0];
    for (int k = 0; k < 3; ++k) {
      const double w = f[1] * c.frame[3 + k] + f[2] * c.frame[6 + k];
      (k == 0 ? tx : k == 1 ? ty : tz) += w;
    }
  }
  out.shear = std::sqrt(tx * tx + ty * ty + tz * tz);
  return out;
}

double AngleDeg(const Matrix3d& R) {
  const double c = std::clamp((R.trace() - 1) / 2, -1.0, 1.0);
  return std::acos(c) * 180 / std::numbers::pi;
}

// Where fingertip i lives in the scene and where its targets start.
struct Fingertip {
  int geom = -1, dof = -1, qadr = -1;
  Vec3 normal, center, open;  // contact normal; centre touching the contact and 15 mm back (world, at rest)
  double delta = 0;           // normal admittance offset (m), Admittance::kNormal
  Vec3 offset;                // target - touching centre (hand frame, m)
};

// What the loop saw and was told at the last control tick (per fingertip).
struct Readings {
  std::vector<double> raw, est, truth, observed, shear;
  std::vector<Vec3> observed_force;
  explicit Readings(int n) : raw(n), est(n), truth(n), observed(n), shear(n), observed_force(n) {}
};

class TrialRun {
 public:
  TrialRun(const GraspSetup& setup, int trial, Scene& scene)
      : cfg_(setup.config()), im_(setup.impl()), sc_(scene), m_(scene.m), d_(scene.d), nf_(im_.n_fingers),
        trial_(trial), readings_(nf_) {
    res_.trial = trial;
    res_.seed = SplitMix(cfg_.seed * 0x100000001b3ULL + static_cast<uint64_t>(trial));
    est_opt_.method = cfg_.estimator;
    kd_ = 2 * cfg_.damping_ratio * std::sqrt(cfg_.kp * cfg_.fingertip_mass);
  }

  absl::Status DrawSensors();
  void LocateFingertips();
  absl::Status Simulate();
  TrialResult Finish();

 private:
  void ControlTick(double t, Phase phase, const HandMotion& hm);
  void ReadSensors(double t);
  void Observe(int tick, Phase phase);
  void UpdateTargets(int tick);
  void TrackConvergence(double t, const std::vector<double>& desired);
  void AccumulateForceError(const std::vector<double>& desired);
  void TrackObjectPose(const HandMotion& hm, double* slip, double* rot);
  void RecordTrace(double t, Phase phase, const std::vector<double>& desired, double slip, double rot);
  void ApplyFingertipPd(double t, Phase phase, const HandMotion& hm);

  const GraspConfig& cfg_;
  const GraspSetup::Impl& im_;
  Scene& sc_;
  mjModel* m_;
  mjData* d_;
  const int nf_;
  const int trial_;
  TrialResult res_;
  std::vector<SensorChannel> channels_;
  std::vector<Fingertip> tips_;
  int object_body_ = -1, obj_q_ = -1;
  estimator::EstimateOptions est_opt_;
  double kd_ = 0;
  Readings readings_;
  bool est_ok_ = false;
  double err_sum_ = 0, fb_sum_ = 0;
  long err_n_ = 0;
  double ok_since_ = -1;
  bool lift_started_ = false;
  Vec3 p_lift_ = Vec3::Zero();
  Matrix3d R_lift_ = Matrix3d::Identity();
  bool dropped_ = false;
};

// Sensors: same draws for either feedback mode.
absl::Status TrialRun::DrawSensors() {
  std::mt19937_64 rng(res_.seed);
  for (int i = 0; i < nf_; ++i) {
    sim::SensorModel model;
    if (cfg_.sensors == SensorMode::kGeoDexRandom) model = DrawGeoDexModel(cfg_.error_ranges, rng);
    else if (cfg_.sensors == SensorMode::kModel) model = cfg_.sensor_model;
    auto ch = SensorChannel::Create(model, SplitMix(res_.seed + 17 * (i + 1)));
    if (!ch.ok()) return ch.status();
    channels_.push_back(std::move(*ch));
    res_.sensor_models.push_back(model);
  }
  return absl::OkStatus();
}

void TrialRun::LocateFingertips() {
  object_body_ = sc_.Body("object");
  obj_q_ = m_->jnt_qposadr[sc_.Joint("object_free")];
  tips_.resize(nf_);
  for (int i = 0; i < nf_; ++i) {
    Fingertip& f = tips_[i];
    f.geom = sc_.Geom(absl::StrCat("f", i, "g").c_str());
    const int jx = sc_.Joint(absl::StrCat("f", i, "x").c_str());
    f.dof = m_->jnt_dofadr[jx];
    f.qadr = m_->jnt_qposadr[jx];
    const planner::Contact& c = im_.base.contacts[i];
    f.normal = c.normal.normalized();
    f.center = im_.rest_origin + c.position - f.normal * cfg_.fingertip_radius;
    f.open = f.center - f.normal * kOpenGap;
    f.delta = im_.tick_desired[0][i] / cfg_.kp;
    f.offset = im_.tick_force[0][i] / cfg_.kp;
  }
}

absl::Status TrialRun::Simulate() {
  const double dt = m_->opt.timestep;
  const int steps_per_tick = std::max(1, static_cast<int>(std::lround(1.0 / (cfg_.control_rate * dt))));
  const int total_steps = static_cast<int>(std::ceil(im_.timeline.t_end / dt));
  for (int k = 0; k <= total_steps && !dropped_; ++k) {
    const double t = k * dt;
    const Phase phase = im_.timeline.At(t);
    const HandMotion hm = im_.Motion(t);
    if (k % steps_per_tick == 0) ControlTick(t, phase, hm);
    ApplyFingertipPd(t, phase, hm);
    mj_step(m_, d_);
    if (!std::isfinite(d_->qpos[obj_q_])) return absl::InternalError("mujoco: simulation diverged");
  }
  return absl::OkStatus();
}

void TrialRun::ControlTick(double t, Phase phase, const HandMotion& hm) {
  const int j = std::min(im_.ticks - 1, static_cast<int>(std::lround(t * cfg_.control_rate)));
  const std::vector<double>& desired = im_.tick_desired[j];
  ReadSensors(t);
  Observe(j, phase);
  if (phase != Phase::kClose) {
    UpdateTargets(j);
    if (phase == Phase::kSettle || phase == Phase::kHold) TrackConvergence(t, desired);
  }
  if (phase == Phase::kHold || phase == Phase::kLift || phase == Phase::kHoldLifted) AccumulateForceError(desired);
  double slip = 0, rot = 0;
  if (phase == Phase::kLift || phase == Phase::kHoldLifted) TrackObjectPose(hm, &slip, &rot);
  if (trial_ < cfg_.trace_trials) RecordTrace(t, phase, desired, slip, rot);
}

// True contact forces through each fingertip's sensor channel.
void TrialRun::ReadSensors(double t) {
  Readings& r = readings_;
  for (int i = 0; i < nf_; ++i) {
    const FingerContact fc = MeasureFinger(m_, d_, tips_[i].geom, object_body_);
    r.truth[i] = fc.normal;
    r.shear[i] = fc.shear;
    r.raw[i] = channels_[i].Step(t, fc.normal, fc.shear) / channels_[i].model().gain;
  }
}

// The estimate from the readings, and what the loop is told (raw readings as
// force vectors r_i n_i when the feedback is raw or the estimator fails).
void TrialRun::Observe(int tick, Phase phase) {
  Readings& r = readings_;
  auto e = estimator::EstimateForces(im_.tick_problem[tick], r.raw, est_opt_);
  est_ok_ = e.ok() && e->status == estimator::EstimateStatus::kOk;
  for (int i = 0; i < nf_; ++i) r.est[i] = est_ok_ ? e->normal_forces[i] : r.raw[i];
  if (!est_ok_ && phase != Phase::kClose) ++res_.estimate_failures;
  r.observed = cfg_.feedback == Feedback::kRaw ? r.raw : r.est;
  for (int i = 0; i < nf_; ++i)
    r.observed_force[i] = cfg_.feedback == Feedback::kRaw || !est_ok_ ? Vec3(r.raw[i] * tips_[i].normal) : e->forces[i];
}

// The admittance law (Admittance::kFull or kNormal) on the fingertip targets.
void TrialRun::UpdateTargets(int tick) {
  const std::vector<double>& desired = im_.tick_desired[tick];
  const std::vector<Vec3>& desired_force = im_.tick_force[tick];  // object frame = hand frame
  const Readings& r = readings_;
  for (int i = 0; i < nf_; ++i) {
    Fingertip& f = tips_[i];
    if (cfg_.admittance == Admittance::kFull) {
      Vec3 step = cfg_.admittance_gain * (desired_force[i] - r.observed_force[i]) / cfg_.kp;
      if (step.norm() > kMaxTargetStep) step *= kMaxTargetStep / step.norm();
      f.offset += step;
      if (f.offset.norm() > 0.03) f.offset *= 0.03 / f.offset.norm();
    } else {
      const double step = std::clamp(cfg_.admittance_gain * (desired[i] - r.observed[i]) / cfg_.kp,
                                     -kMaxTargetStep, kMaxTargetStep);
      f.delta = std::clamp(f.delta + step, -0.01, 0.03);
      const Vec3& fd = desired_force[i];
      f.offset = f.normal * f.delta + (fd - f.normal * f.normal.dot(fd)) / cfg_.kp;
    }
  }
}

// Convergence of the loop's own error (settle and hold): below max(0.1 N,
// 10 %) on every fingertip for 0.1 s.
void TrialRun::TrackConvergence(double t, const std::vector<double>& desired) {
  bool ok = true;
  for (int i = 0; i < nf_; ++i)
    ok = ok && std::abs(desired[i] - readings_.observed[i]) < std::max(0.1, 0.1 * desired[i]);
  if (!ok) ok_since_ = -1;
  else if (ok_since_ < 0) ok_since_ = t;
  if (ok && res_.converge_time < 0 && t - ok_since_ >= 0.1 - 1e-9)
    res_.converge_time = ok_since_ - im_.timeline.t_settle;
}

void TrialRun::AccumulateForceError(const std::vector<double>& desired) {
  for (int i = 0; i < nf_; ++i) {
    err_sum_ += std::abs(readings_.truth[i] - desired[i]);
    fb_sum_ += std::abs(readings_.observed[i] - readings_.truth[i]);
  }
  ++err_n_;
}

// Object pose versus where the hand holds it: the hand's motion since the
// lift started applied to the object's pose then (the hand is at rest when
// the lift starts).
void TrialRun::TrackObjectPose(const HandMotion& hm, double* slip, double* rot) {
  const double* q = d_->qpos + obj_q_;
  const Vec3 p(q[0], q[1], q[2]);
  const Matrix3d R = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).toRotationMatrix();
  if (!lift_started_) {
    lift_started_ = true;
    p_lift_ = p;
    R_lift_ = R;
  }
  const Vec3 p_exp = im_.Apply(hm, p_lift_);
  const Matrix3d R_exp = hm.R * R_lift_;
  *slip = (p - p_exp).norm();
  *rot = AngleDeg(R * R_exp.transpose());
  res_.max_slip = std::max(res_.max_slip, *slip);
  res_.max_rotation_deg = std::max(res_.max_rotation_deg, *rot);
  if (*slip > cfg_.drop_distance) dropped_ = true;
}

void TrialRun::RecordTrace(double t, Phase phase, const std::vector<double>& desired, double slip, double rot) {
  TraceSample s;
  s.t = t;
  s.phase = phase;
  s.desired = desired;
  s.raw = readings_.raw;
  s.estimated = readings_.est;
  s.truth = readings_.truth;
  s.slip = slip;
  s.rotation_deg = rot;
  res_.trace.push_back(std::move(s));
}

// Fingertip PD in fingertip space (J = I), gravity compensated: a
// minimum-jerk close onto the targets, then the targets carried by the hand.
void TrialRun::ApplyFingertipPd(double t, Phase phase, const HandMotion& hm) {
  for (const Fingertip& f : tips_) {
    Vec3 target, vtarget = Vec3::Zero();
    if (phase == Phase::kClose) {
      double s, ds, dds;
      MinJerk(t / cfg_.phases.close, &s, &ds, &dds);
      const Vec3 goal = f.center + f.offset;
      target = f.open + s * (goal - f.open);
      vtarget = ds / cfg_.phases.close * (goal - f.open);
    } else {
      const Vec3 x0 = f.center + f.offset;
      target = im_.Apply(hm, x0);
      vtarget = im_.Velocity(hm, x0);
    }
    for (int a = 0; a < 3; ++a) {
      const double x = f.open[a] + d_->qpos[f.qadr + a];
      const double v = d_->qvel[f.dof + a];
      d_->qfrc_applied[f.dof + a] =
          cfg_.kp * (target[a] - x) + kd_ * (vtarget[a] - v) + (a == 2 ? cfg_.fingertip_mass * 9.81 : 0.0);
    }
  }
}

// Scores: mean force errors and the first failure criterion met.
TrialResult TrialRun::Finish() {
  res_.dropped = dropped_;
  res_.force_error = err_n_ > 0 ? err_sum_ / (err_n_ * nf_) : 0;
  res_.feedback_error = err_n_ > 0 ? fb_sum_ / (err_n_ * nf_) : 0;
  if (dropped_) res_.failure = "dropped";
  else if (res_.max_slip >= cfg_.max_slip) res_.failure = absl::StrFormat("slip %.1f mm", res_.max_slip * 1e3);
  else if (res_.max_rotation_deg >= cfg_.max_rotation_deg)
    res_.failure = absl::StrFormat("rotation %.2f deg", res_.max_rotation_deg);
  res_.success = res_.failure.empty();
  res_.sim_seconds = d_->time;
  return std::move(res_);
}

}  // namespace

absl::StatusOr<TrialResult> RunGraspTrial(const GraspSetup& setup, int trial) {
  const auto wall0 = std::chrono::steady_clock::now();
  if (trial < 0) return absl::InvalidArgumentError(absl::StrFormat("trial: must be >= 0, got %d", trial));
  auto scene = Scene::FromMjcf(setup.mjcf());
  if (!scene.ok()) return scene.status();
  TrialRun run(setup, trial, **scene);
  if (absl::Status s = run.DrawSensors(); !s.ok()) return s;
  run.LocateFingertips();
  if (absl::Status s = run.Simulate(); !s.ok()) return s;
  TrialResult res = run.Finish();
  res.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return res;
}

absl::StatusOr<BatchSummary> RunGraspBatch(const GraspConfig& config, int trials,
                                           const std::function<void(int)>& progress) {
  if (trials < 1) return absl::InvalidArgumentError(absl::StrFormat("trials: must be >= 1, got %d", trials));
  auto setup = GraspSetup::Create(config);
  if (!setup.ok()) return setup.status();
  BatchSummary b;
  b.object = config.object;
  b.feedback = config.feedback;
  b.trials = trials;
  double conv = 0;
  for (int k = 0; k < trials; ++k) {
    auto r = RunGraspTrial(**setup, k);
    if (!r.ok()) return r.status();
    b.successes += r->success;
    b.drops += r->dropped;
    b.wall_seconds += r->wall_seconds;
    b.sim_seconds += r->sim_seconds;
    if (r->converge_time >= 0) conv += r->converge_time, ++b.converged;
    b.results.push_back(std::move(*r));
    if (progress) progress(k + 1);
  }
  double s = 0, s2 = 0, fb = 0;
  for (const TrialResult& r : b.results) s += r.force_error, s2 += r.force_error * r.force_error, fb += r.feedback_error;
  b.force_error_mean = s / trials;
  b.force_error_std = trials > 1 ? std::sqrt(std::max(0.0, (s2 - s * s / trials) / (trials - 1))) : 0.0;
  b.feedback_error_mean = fb / trials;
  b.converge_time_mean = b.converged > 0 ? conv / b.converged : -1;
  return b;
}

}  // namespace tactforce::experiment
