// One closed-loop grasp trial in MuJoCo and batches of them. A trial draws
// its sensors from (seed, trial) — the same draws for raw and estimated
// feedback — then steps the physics at 1 ms; every control tick it reads the
// fingertips' true contact forces through their sensor channels, estimates
// the forces (or takes the raw readings), moves the fingertip targets by the
// admittance law and scores the object's pose against where the hand's
// motion puts it; every physics step a PD in fingertip space tracks the
// targets. The steps below are the methods of `TrialRun`, in that order.
// With taxel sensors each fingertip is a sim::TaxelArray fed MuJoCo's contact
// point and force, and at the end of the close the contacts sensed by the
// taxels replace the grasp specification's for planning and estimation.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <random>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "grasp_internal.h"
#include "scene.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

using Eigen::Matrix3d;
using planner::Vec3;

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
    if (c.geom1 == finger_geom)
      other = c.geom2;
    else if (c.geom2 == finger_geom)
      other = c.geom1;
    else
      continue;
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

// A force error with its tangential part (off `normal`) shrunk by `bound`
// (N): what of it lies within the error a wrong normal alone can make.
Vec3 TrustedError(const Vec3& error, const Vec3& normal, double bound) {
  if (!(bound > 0)) return error;
  const Vec3 en = normal * normal.dot(error), et = error - en;
  const double t = et.norm();
  return t > bound ? Vec3(en + et * (1 - bound / t)) : en;
}

// The taxel fingertip's frame (fingertip -> world) for a contact whose
// normal (into the object) is `normal`: z = normal when cap_deg is 0, so the
// contact is centred on the apex taxel; otherwise the fingertip is turned so
// the contact lands at a polar angle from the apex drawn uniformly by area
// over the cap (cos uniform in [cos cap, 1]) and a uniform azimuth.
Matrix3d FingertipFrame(const Vec3& normal, double cap_deg, uint64_t seed) {
  Matrix3d frame;
  const Vec3 x = normal.unitOrthogonal();
  frame.col(0) = x;
  frame.col(1) = normal.cross(x);
  frame.col(2) = normal;
  if (!(cap_deg > 0)) return frame;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  const double cos_cap = std::cos(cap_deg * std::numbers::pi / 180);
  const double c = 1 - (1 - cos_cap) * u01(rng), s = std::sqrt(std::max(0.0, 1 - c * c));
  const double az = 2 * std::numbers::pi * u01(rng);
  // The contact direction in the fingertip frame, d; frame^T normal = d.
  const Vec3 d(s * std::cos(az), s * std::sin(az), c);
  return frame *
         Eigen::Quaterniond::FromTwoVectors(Vec3::UnitZ(), d).toRotationMatrix().transpose();
}

double AngleDeg(const Matrix3d& R) {
  const double c = std::clamp((R.trace() - 1) / 2, -1.0, 1.0);
  return std::acos(c) * 180 / std::numbers::pi;
}

// The force the object exerts on one fingertip geom (world, N) and where it
// acts (normal-force-weighted mean of the contact points, world, m).
struct FingerWrench {
  double normal = 0;
  Vec3 force = Vec3::Zero(), point = Vec3::Zero();
};
FingerWrench MeasureFingerForce(const mjModel* m, const mjData* d, int finger_geom,
                                int object_body) {
  FingerWrench out;
  for (int i = 0; i < d->ncon; ++i) {
    const mjContact& c = d->contact[i];
    if (c.geom1 != finger_geom && c.geom2 != finger_geom) continue;
    const int other = c.geom1 == finger_geom ? c.geom2 : c.geom1;
    if (m->geom_bodyid[other] != object_body || c.efc_address < 0) continue;
    mjtNum f[6];
    mj_contactForce(m, d, i, f);
    // The contact frame's normal points from geom1 to geom2: the force on geom2.
    const double sign = c.geom2 == finger_geom ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k)
      out.force[k] += sign * (f[0] * c.frame[k] + f[1] * c.frame[3 + k] + f[2] * c.frame[6 + k]);
    out.point += f[0] * Vec3(c.pos[0], c.pos[1], c.pos[2]);
    out.normal += f[0];
  }
  if (out.normal > 0) out.point /= out.normal;
  return out;
}

// Where fingertip i lives in the scene and where its targets start.
struct Fingertip {
  int geom = -1, dof = -1, qadr = -1;
  Vec3 normal, center,
      open;          // contact normal; centre touching the contact and 15 mm back (world, at rest)
  double delta = 0;  // normal admittance offset (m), Admittance::kNormal
  Vec3 offset;       // target - touching centre (hand frame, m)
  Matrix3d frame = Matrix3d::Identity();  // taxel fingertip frame -> world (FingertipFrame)
};

// What the loop saw and was told at the last control tick (per fingertip).
struct Readings {
  std::vector<double> raw, est, truth, observed, shear;
  std::vector<Vec3> observed_force;
  bool estimate_used = false;  // observed = the estimate (not the raw readings)
  explicit Readings(int n) : raw(n), est(n), truth(n), observed(n), shear(n), observed_force(n) {}
};

class TrialRun {
 public:
  TrialRun(const GraspSetup& setup, int trial, Scene& scene)
      : cfg_(setup.config()),
        im_(setup.impl()),
        sc_(scene),
        m_(scene.m),
        d_(scene.d),
        nf_(im_.n_fingers),
        trial_(trial),
        readings_(nf_) {
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
  void TrackObjectPose(Phase phase, const HandMotion& hm, double* slip, double* rot);
  void RecordTrace(double t, Phase phase, const std::vector<double>& desired, double slip,
                   double rot);
  void ApplyFingertipPd(double t, Phase phase, const HandMotion& hm);
  void ReadTaxels(double t);
  sim::Taxel SensedContact(const sim::FingertipReading& taxels, const Vec3& true_point) const;
  void ApplyFault(double t);
  void SenseContactsAndReplan(int tick);
  void TrackSwitched(const std::vector<double>& desired);
  Feedback ActiveFeedback(Phase phase) const;
  const std::vector<double>& Desired(int tick) const {
    return replanned_ && tick >= plan_first_ ? plans_.desired[tick - plan_first_]
                                             : im_.tick_desired[tick];
  }
  const std::vector<Vec3>& DesiredForce(int tick) const {
    return replanned_ && tick >= plan_first_ ? plans_.force[tick - plan_first_]
                                             : im_.tick_force[tick];
  }
  const planner::PlanProblem& Problem(int tick) const {
    return replanned_ && tick >= plan_first_ ? plans_.problem[tick - plan_first_]
                                             : im_.tick_problem[tick];
  }

  const GraspConfig& cfg_;
  const GraspSetup::Impl& im_;
  Scene& sc_;
  mjModel* m_;
  mjData* d_;
  const int nf_;
  const int trial_;
  TrialResult res_;
  std::vector<SensorChannel> channels_;
  std::vector<sim::TaxelArray> arrays_;             // taxel sensors
  std::vector<Vec3> sensed_point_, sensed_normal_;  // world, from the taxels at the last tick
  bool sensed_ = false, replanned_ = false;
  int plan_first_ = 0;
  TickPlans plans_;
  CauseTracker causes_{nf_};
  bool failure_seen_ = false;
  bool switch_started_ = false;
  Vec3 p_switch_ = Vec3::Zero();
  std::vector<double> switched_sum_;
  long switched_n_ = 0;
  std::vector<Fingertip> tips_;
  int object_body_ = -1, obj_q_ = -1;
  estimator::EstimateOptions est_opt_;
  double kd_ = 0;
  Readings readings_;
  bool est_ok_ = false;
  double err_sum_ = 0, fb_sum_ = 0, squeeze_sum_ = 0;
  std::vector<double> finger_err_, finger_loop_;
  long err_n_ = 0;
  double ok_since_ = -1;
  bool pose_tracked_ = false,
       lift_started_ = false;  // the object's pose at the settle's and the lift's start
  Vec3 p_ref_ = Vec3::Zero(), p_lift_ = Vec3::Zero();
  Matrix3d R_ref_ = Matrix3d::Identity();
  bool dropped_ = false;
};

// Sensors: same draws for either feedback mode.
absl::Status TrialRun::DrawSensors() {
  std::mt19937_64 rng(res_.seed);
  if (cfg_.sensor_array == SensorArray::kTaxel) {
    const sim::FingertipGeometry& geometry = im_.fingertip;
    for (int i = 0; i < nf_; ++i) {
      TF_ASSIGN_OR_RETURN(
          auto a,
          sim::TaxelArray::Create(cfg_.taxel_ranges, SplitMix(res_.seed + 31 * (i + 1)), geometry));
      arrays_.push_back(std::move(a));
    }
    sensed_point_.assign(nf_, Vec3::Zero());
    sensed_normal_.assign(nf_, Vec3::Zero());
    return absl::OkStatus();
  }
  for (int i = 0; i < nf_; ++i) {
    sim::SensorModel model;
    if (cfg_.sensors == SensorMode::kGeoDexRandom)
      model = DrawGeoDexModel(cfg_.error_ranges, rng);
    else if (cfg_.sensors == SensorMode::kModel)
      model = cfg_.sensor_model;
    TF_ASSIGN_OR_RETURN(auto ch, SensorChannel::Create(model, SplitMix(res_.seed + 17 * (i + 1))));
    channels_.push_back(std::move(ch));
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
    // The fingertips only translate, so the frame drawn here holds all trial.
    f.frame = FingertipFrame(f.normal, cfg_.contact_cap_deg, SplitMix(res_.seed + 43 * (i + 1)));
    if (cfg_.sensor_array == SensorArray::kTaxel)
      res_.contact_polar_deg.push_back(
          std::acos(std::clamp(f.frame.col(2).dot(f.normal), -1.0, 1.0)) * 180 / std::numbers::pi);
  }
}

absl::Status TrialRun::Simulate() {
  const double dt = m_->opt.timestep;
  const int steps_per_tick =
      std::max(1, static_cast<int>(std::lround(1.0 / (cfg_.control_rate * dt))));
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
  ReadSensors(t);
  ApplyFault(t);
  if (cfg_.sensor_array == SensorArray::kTaxel && phase != Phase::kClose && !sensed_)
    SenseContactsAndReplan(j);
  const std::vector<double>& desired = Desired(j);
  Observe(j, phase);
  if (phase != Phase::kClose) {
    UpdateTargets(j);
    if (phase == Phase::kSettle || phase == Phase::kHold) TrackConvergence(t, desired);
  }
  if (phase == Phase::kHold || phase == Phase::kLift || phase == Phase::kHoldLifted)
    AccumulateForceError(desired);
  // Judged from the settle to the end of the lifted hold: the causes and the object's pose.
  const bool judged = phase == Phase::kSettle || phase == Phase::kHold || phase == Phase::kLift ||
                      phase == Phase::kHoldLifted;
  if (judged && !failure_seen_) causes_.Tick(t, readings_.truth, readings_.raw);
  double slip = 0, rot = 0;
  if (judged) {
    TrackObjectPose(phase, hm, &slip, &rot);
    const bool failed = dropped_ || slip >= cfg_.max_slip || rot >= cfg_.max_rotation_deg;
    if (failed && !failure_seen_) res_.failure_time = t;
    failure_seen_ = failure_seen_ || failed;
  }
  if (phase == Phase::kSwitched) TrackSwitched(desired);
  if (trial_ < cfg_.trace_trials) RecordTrace(t, phase, desired, slip, rot);
}

// True contact forces through each fingertip's sensor channel.
void TrialRun::ReadSensors(double t) {
  if (cfg_.sensor_array == SensorArray::kTaxel) return ReadTaxels(t);
  Readings& r = readings_;
  for (int i = 0; i < nf_; ++i) {
    const FingerContact fc = MeasureFinger(m_, d_, tips_[i].geom, object_body_);
    r.truth[i] = fc.normal;
    r.shear[i] = fc.shear;
    r.raw[i] = channels_[i].Step(t, fc.normal, fc.shear) / channels_[i].model().gain;
  }
}

// MuJoCo's contact point and force into each fingertip's taxel array (its
// frame: the hemisphere's centre at (0, 0, body_length) is the sphere's
// centre); the reading is the taxels' sum, the sensed contact their
// force-weighted location and normal, back in the world.
void TrialRun::ReadTaxels(double t) {
  Readings& r = readings_;
  const Vec3 tip_centre(0, 0, sim::FingertipGeometry{}.body_length);
  for (int i = 0; i < nf_; ++i) {
    const Fingertip& f = tips_[i];
    const FingerWrench w = MeasureFingerForce(m_, d_, f.geom, object_body_);
    const Vec3 centre = f.open + Vec3(d_->qpos[f.qadr], d_->qpos[f.qadr + 1], d_->qpos[f.qadr + 2]);
    Vec3 point = tip_centre + cfg_.fingertip_radius * Vec3::UnitZ();
    if (w.normal > 0 && (w.point - centre).norm() > 1e-9)
      point = tip_centre +
              cfg_.fingertip_radius * (f.frame.transpose() * (w.point - centre)).normalized();
    const sim::TaxelArrayReading& out = arrays_[i].Step(t, point, f.frame.transpose() * w.force);
    r.truth[i] = w.normal;
    r.shear[i] = std::sqrt(std::max(0.0, w.force.squaredNorm() - w.normal * w.normal));
    r.raw[i] = out.fingertip.force;
    const sim::Taxel sensed = SensedContact(out.fingertip, point);
    sensed_point_[i] = centre + f.frame * (sensed.position - tip_centre);
    sensed_normal_[i] = f.frame * sensed.normal;
  }
}

// The contact a fingertip reports (fingertip frame; GraspConfig::contact_sensing)
// from its taxels' aggregate and, for the what-if modes, the true contact
// point on its surface. A zero normal: nothing sensed.
sim::Taxel TrialRun::SensedContact(const sim::FingertipReading& taxels,
                                   const Vec3& true_point) const {
  const sim::FingertipGeometry& g = im_.fingertip;
  sim::Taxel out{taxels.location, taxels.normal};
  if (out.normal.norm() < 0.5) return out;
  const Vec3 true_normal = (true_point - Vec3(0, 0, g.body_length)).normalized();
  switch (cfg_.contact_sensing) {
    case ContactSensing::kTaxelMean:
      break;
    case ContactSensing::kSurface:
      out = sim::ProjectOntoFingertip(g, taxels.location);
      break;
    case ContactSensing::kTrueNormal:
      out.normal = true_normal;
      break;
    case ContactSensing::kTrueLocation:
      out.position = true_point;
      break;
    case ContactSensing::kTruth:
      out = {true_point, true_normal};
      break;
  }
  return out;
}

// The constructed fault (GraspConfig::fault) on one fingertip's reading.
void TrialRun::ApplyFault(double t) {
  const SensorFault& fault = cfg_.fault;
  if (fault.kind == SensorFault::Kind::kNone || t < fault.start) return;
  double& raw = readings_.raw[fault.finger];
  raw = fault.kind == SensorFault::Kind::kDead ? 0.0 : raw + fault.magnitude;
}

// End of the close: the contacts the taxels sense (object frame) replace the
// specification's where a fingertip reads a force, and the rest of the trial
// is re-planned on them (GeoDEx Sec. IV: contact locations and normals from
// the tactile arrays). A failed re-plan keeps the specification's plan.
void TrialRun::SenseContactsAndReplan(int tick) {
  sensed_ = true;
  const double* q = d_->qpos + obj_q_;
  const Vec3 p(q[0], q[1], q[2]);
  const Matrix3d Rt = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).toRotationMatrix().transpose();
  std::vector<planner::Contact> contacts = im_.base.contacts;
  double loc_err = 0, ang_err = 0;
  for (int i = 0; i < nf_; ++i) {
    if (!(readings_.raw[i] > 0) || sensed_normal_[i].norm() < 0.5) continue;
    planner::Contact& c = contacts[i];
    c.position = Rt * (sensed_point_[i] - p);
    c.normal = (Rt * sensed_normal_[i]).normalized();
    loc_err += (c.position - im_.base.contacts[i].position).norm();
    ang_err += AngleDeg(
        Eigen::Quaterniond::FromTwoVectors(im_.base.contacts[i].normal.normalized(), c.normal)
            .toRotationMatrix());
    ++res_.contacts_sensed;
  }
  if (res_.contacts_sensed > 0) {
    res_.contact_location_error = loc_err / res_.contacts_sensed;
    res_.contact_normal_error_deg = ang_err / res_.contacts_sensed;
  }
  auto plans = PlanTickRange(cfg_, im_, contacts, tick);
  if (!plans.ok()) {
    res_.replan_failed = true;
    return;
  }
  plans_ = *std::move(plans);
  plan_first_ = tick;
  replanned_ = true;
  for (int i = 0; i < nf_; ++i)
    if (contacts[i].normal != im_.base.contacts[i].normal)
      tips_[i].normal = (Rt.transpose() * contacts[i].normal);
}

Feedback TrialRun::ActiveFeedback(Phase phase) const {
  if (phase != Phase::kSwitched) return cfg_.feedback;
  return cfg_.feedback == Feedback::kRaw ? Feedback::kEstimated : Feedback::kRaw;
}

// The switched phase: force error per fingertip and the object's motion.
void TrialRun::TrackSwitched(const std::vector<double>& desired) {
  const double* q = d_->qpos + obj_q_;
  const Vec3 p(q[0], q[1], q[2]);
  if (!switch_started_) switch_started_ = true, p_switch_ = p, switched_sum_.assign(nf_, 0.0);
  for (int i = 0; i < nf_; ++i) switched_sum_[i] += std::abs(readings_.truth[i] - desired[i]);
  ++switched_n_;
  res_.switched_motion = std::max(res_.switched_motion, (p - p_switch_).norm());
}

// The estimate from the readings, and what the loop is told (raw readings as
// force vectors r_i n_i when the feedback is raw or the estimator fails).
void TrialRun::Observe(int tick, Phase phase) {
  Readings& r = readings_;
  auto e = estimator::EstimateForces(Problem(tick), r.raw, est_opt_);
  est_ok_ = e.ok() && e->status == estimator::EstimateStatus::kOk;
  for (int i = 0; i < nf_; ++i) r.est[i] = est_ok_ ? e->normal_forces[i] : r.raw[i];
  if (!est_ok_ && phase != Phase::kClose) ++res_.estimate_failures;
  const Feedback feedback = ActiveFeedback(phase);
  r.observed = feedback == Feedback::kRaw ? r.raw : r.est;
  r.estimate_used = feedback == Feedback::kEstimated && est_ok_;
  for (int i = 0; i < nf_; ++i)
    r.observed_force[i] =
        feedback == Feedback::kRaw || !est_ok_ ? Vec3(r.raw[i] * tips_[i].normal) : e->forces[i];
}

// The admittance law (Admittance::kFull or kNormal) on the fingertip targets.
void TrialRun::UpdateTargets(int tick) {
  const std::vector<double>& desired = Desired(tick);
  const std::vector<Vec3>& desired_force = DesiredForce(tick);  // object frame = hand frame
  const Readings& r = readings_;
  for (int i = 0; i < nf_; ++i) {
    Fingertip& f = tips_[i];
    if (cfg_.admittance == Admittance::kFull) {
      const Vec3 error = TrustedError(
          desired_force[i] - r.observed_force[i], f.normal,
          r.estimate_used ? r.observed_force[i].norm() * im_.sin_normal_uncertainty : 0.0);
      Vec3 step = cfg_.admittance_gain * error / cfg_.kp;
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
  if (!ok)
    ok_since_ = -1;
  else if (ok_since_ < 0)
    ok_since_ = t;
  if (ok && res_.converge_time < 0 && t - ok_since_ >= 0.1 - 1e-9)
    res_.converge_time = ok_since_ - im_.timeline.t_settle;
}

void TrialRun::AccumulateForceError(const std::vector<double>& desired) {
  finger_err_.resize(nf_, 0.0);
  finger_loop_.resize(nf_, 0.0);
  for (int i = 0; i < nf_; ++i) {
    err_sum_ += std::abs(readings_.truth[i] - desired[i]);
    fb_sum_ += std::abs(readings_.observed[i] - readings_.truth[i]);
    finger_err_[i] += std::abs(readings_.truth[i] - desired[i]);
    finger_loop_[i] += std::abs(readings_.observed[i] - desired[i]);
    squeeze_sum_ += readings_.truth[i];
    const double mu = im_.base.contacts[i].friction;  // the simulated (true) mu
    if (readings_.truth[i] >= 0.05 && mu > 0)
      res_.min_slip_margin =
          std::min(res_.min_slip_margin, 1 - readings_.shear[i] / (mu * readings_.truth[i]));
  }
  ++err_n_;
}

// Object pose versus where the hand holds it, from the settle on: the hand's
// motion since then (none until the lift) applied to the object's pose when
// the settle started. The grasp must keep the object still on the table
// before the lift as well (GeoDEx IV-C: the pose "remains static" over the
// 20 s hold; success = no noticeable movement), so a loop that moves the
// object before the lift fails too. Dropped (the trial ends): from the lift
// on, drop_distance away from where the hand's motion since the lift's start
// puts the object's pose then.
void TrialRun::TrackObjectPose(Phase phase, const HandMotion& hm, double* slip, double* rot) {
  const double* q = d_->qpos + obj_q_;
  const Vec3 p(q[0], q[1], q[2]);
  const Matrix3d R = Eigen::Quaterniond(q[3], q[4], q[5], q[6]).toRotationMatrix();
  if (!pose_tracked_) pose_tracked_ = true, p_ref_ = p, R_ref_ = R;
  *slip = (p - im_.Apply(hm, p_ref_)).norm();
  *rot = AngleDeg(R * (hm.R * R_ref_).transpose());
  res_.max_slip = std::max(res_.max_slip, *slip);
  res_.max_rotation_deg = std::max(res_.max_rotation_deg, *rot);
  if (phase == Phase::kSettle || phase == Phase::kHold) {
    res_.max_slip_before_lift = std::max(res_.max_slip_before_lift, *slip);
    res_.max_rotation_before_lift_deg = std::max(res_.max_rotation_before_lift_deg, *rot);
    return;
  }
  if (!lift_started_) lift_started_ = true, p_lift_ = p;
  if ((p - im_.Apply(hm, p_lift_)).norm() > cfg_.drop_distance) dropped_ = true;
}

void TrialRun::RecordTrace(double t, Phase phase, const std::vector<double>& desired, double slip,
                           double rot) {
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
      d_->qfrc_applied[f.dof + a] = cfg_.kp * (target[a] - x) + kd_ * (vtarget[a] - v) +
                                    (a == 2 ? cfg_.fingertip_mass * 9.81 : 0.0);
    }
  }
}

// Scores: mean force errors and the first failure criterion met.
TrialResult TrialRun::Finish() {
  res_.dropped = dropped_;
  res_.force_error = err_n_ > 0 ? err_sum_ / (err_n_ * nf_) : 0;
  res_.feedback_error = err_n_ > 0 ? fb_sum_ / (err_n_ * nf_) : 0;
  res_.squeeze = err_n_ > 0 ? squeeze_sum_ / err_n_ : 0;
  for (size_t i = 0; i < finger_err_.size(); ++i) {
    res_.finger_force_error.push_back(finger_err_[i] / err_n_);
    res_.finger_loop_error.push_back(finger_loop_[i] / err_n_);
    res_.loop_error += finger_loop_[i] / (err_n_ * nf_);
  }
  if (res_.failure_time >= 0 && res_.failure_time < im_.timeline.t_lift)
    res_.failure =
        absl::StrFormat("moved before the lift (slip %.1f mm, rotation %.2f deg)%s",
                        res_.max_slip_before_lift * 1e3, res_.max_rotation_before_lift_deg,
                        dropped_ ? ", then dropped" : "");
  else if (dropped_)
    res_.failure = "dropped";
  else if (res_.max_slip >= cfg_.max_slip)
    res_.failure = absl::StrFormat("slip %.1f mm", res_.max_slip * 1e3);
  else if (res_.max_rotation_deg >= cfg_.max_rotation_deg)
    res_.failure = absl::StrFormat("rotation %.2f deg", res_.max_rotation_deg);
  res_.success = res_.failure.empty();
  // Tilted: rotated past the threshold while still held (a slip may come with it).
  const bool tilted = !dropped_ && res_.max_rotation_deg >= cfg_.max_rotation_deg;
  res_.cause = causes_.Label(!res_.success, tilted);
  for (double s : switched_sum_)
    res_.switched_force_error.push_back(switched_n_ > 0 ? s / switched_n_ : 0.0);
  res_.sim_seconds = d_->time;
  return std::move(res_);
}

}  // namespace

absl::StatusOr<TrialResult> RunGraspTrial(const GraspSetup& setup, int trial) {
  const auto wall0 = std::chrono::steady_clock::now();
  if (trial < 0)
    return absl::InvalidArgumentError(absl::StrFormat("trial: must be >= 0, got %d", trial));
  TF_ASSIGN_OR_RETURN(auto scene, Scene::FromMjcf(setup.mjcf()));
  TrialRun run(setup, trial, *scene);
  TF_RETURN_IF_ERROR(run.DrawSensors());
  run.LocateFingertips();
  TF_RETURN_IF_ERROR(run.Simulate());
  TrialResult res = run.Finish();
  res.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return res;
}

namespace {

// Mean and sample std of the force error over the trials with success == `ok`.
void MeanStd(const std::vector<TrialResult>& results, bool ok, double* mean, double* std) {
  double s = 0, s2 = 0;
  int n = 0;
  for (const TrialResult& r : results)
    if (r.success == ok) s += r.force_error, s2 += r.force_error * r.force_error, ++n;
  *mean = n > 0 ? s / n : 0.0;
  *std = n > 1 ? std::sqrt(std::max(0.0, (s2 - s * s / n) / (n - 1))) : 0.0;
}

// Table III's split, the failure causes, the taxels' contact sensing and the
// switched phase's force error per fingertip.
void SummariseSplit(BatchSummary* b) {
  MeanStd(b->results, true, &b->force_error_success_mean, &b->force_error_success_std);
  MeanStd(b->results, false, &b->force_error_failure_mean, &b->force_error_failure_std);
  for (FailureCause c : AllFailureCauses()) b->failure_causes[ToString(c)] = 0;
  double loc = 0, l = 0, l2 = 0;
  const size_t n = b->results.size();
  auto add = [&](std::vector<double>* dst, const std::vector<double>& v) {
    if (dst->size() < v.size()) dst->resize(v.size(), 0.0);
    for (size_t i = 0; i < v.size(); ++i) (*dst)[i] += v[i] / n;
  };
  for (const TrialResult& r : b->results) {
    l += r.loop_error, l2 += r.loop_error * r.loop_error;
    add(&b->finger_force_error, r.finger_force_error);
    add(&b->finger_loop_error, r.finger_loop_error);
    if (r.cause != FailureCause::kNone) ++b->failure_causes[ToString(r.cause)];
    b->replan_failures += r.replan_failed;
    loc += r.contact_location_error;
    add(&b->switched_force_error, r.switched_force_error);
  }
  b->contact_location_error_mean = n > 0 ? loc / n : 0.0;
  b->loop_error_mean = n > 0 ? l / n : 0.0;
  b->loop_error_std = n > 1 ? std::sqrt(std::max(0.0, (l2 - l * l / n) / (n - 1))) : 0.0;
}

}  // namespace

absl::StatusOr<BatchSummary> RunGraspBatch(const GraspConfig& config, int trials,
                                           const std::function<void(int)>& progress) {
  if (trials < 1)
    return absl::InvalidArgumentError(absl::StrFormat("trials: must be >= 1, got %d", trials));
  TF_ASSIGN_OR_RETURN(auto setup, GraspSetup::Create(config));
  BatchSummary b;
  b.object = config.object;
  b.feedback = config.feedback;
  b.trials = trials;
  b.finger_names = setup->finger_names();
  double conv = 0;
  for (int k = 0; k < trials; ++k) {
    TF_ASSIGN_OR_RETURN(auto r, RunGraspTrial(*setup, k));
    b.successes += r.success;
    b.drops += r.dropped;
    b.wall_seconds += r.wall_seconds;
    b.sim_seconds += r.sim_seconds;
    if (r.converge_time >= 0) conv += r.converge_time, ++b.converged;
    b.results.push_back(std::move(r));
    if (progress) progress(k + 1);
  }
  double s = 0, s2 = 0, fb = 0;
  for (const TrialResult& r : b.results)
    s += r.force_error, s2 += r.force_error * r.force_error, fb += r.feedback_error;
  b.force_error_mean = s / trials;
  b.force_error_std =
      trials > 1 ? std::sqrt(std::max(0.0, (s2 - s * s / trials) / (trials - 1))) : 0.0;
  b.feedback_error_mean = fb / trials;
  b.converge_time_mean = b.converged > 0 ? conv / b.converged : -1;
  SummariseSplit(&b);
  return b;
}

}  // namespace tactforce::experiment
