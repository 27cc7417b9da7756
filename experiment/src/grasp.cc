#include "tactforce/experiment/grasp.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "scene.h"
#include "tactforce/planner/examples.h"
#include "tactforce/planner/solver.h"

namespace tactforce::experiment {

using planner::Vec3;
using Eigen::Matrix3d;

const char* ToString(GraspObject o) {
  switch (o) {
    case GraspObject::kSphere: return "sphere";
    case GraspObject::kWrench: return "wrench";
    case GraspObject::kCylinder: return "cylinder";
    case GraspObject::kCube: return "cube";
  }
  return "?";
}

absl::StatusOr<GraspObject> ParseGraspObject(std::string_view name) {
  for (GraspObject o : AllGraspObjects())
    if (name == ToString(o)) return o;
  return absl::InvalidArgumentError(
      absl::StrCat("object: unknown '", std::string(name), "' (expected sphere, wrench, cylinder or cube)"));
}

std::vector<GraspObject> AllGraspObjects() {
  return {GraspObject::kSphere, GraspObject::kWrench, GraspObject::kCylinder, GraspObject::kCube};
}

const char* ToString(Feedback f) { return f == Feedback::kRaw ? "raw" : "estimated"; }

absl::StatusOr<Feedback> ParseFeedback(std::string_view name) {
  if (name == "raw") return Feedback::kRaw;
  if (name == "estimated") return Feedback::kEstimated;
  return absl::InvalidArgumentError(absl::StrCat("feedback: unknown '", std::string(name), "' (expected raw or estimated)"));
}

const char* ToString(Admittance a) { return a == Admittance::kFull ? "full" : "normal"; }

absl::StatusOr<Admittance> ParseAdmittance(std::string_view name) {
  if (name == "full") return Admittance::kFull;
  if (name == "normal") return Admittance::kNormal;
  return absl::InvalidArgumentError(
      absl::StrCat("admittance: unknown '", std::string(name), "' (expected full or normal)"));
}

const char* ToString(Phase p) {
  switch (p) {
    case Phase::kClose: return "close";
    case Phase::kSettle: return "settle";
    case Phase::kHold: return "hold";
    case Phase::kLift: return "lift";
    case Phase::kHoldLifted: return "hold";
    case Phase::kPlace: return "place";
  }
  return "?";
}

absl::Status ValidateGraspConfig(const GraspConfig& c) {
  auto bad = [](const std::string& field, const std::string& why) {
    return absl::InvalidArgumentError(absl::StrCat(field, ": ", why));
  };
  auto positive = [&](const char* field, double v) -> absl::Status {
    if (!(v > 0 && std::isfinite(v))) return bad(field, absl::StrFormat("must be > 0, got %g", v));
    return absl::OkStatus();
  };
  const PhaseDurations& p = c.phases;
  for (auto [name, v] : {std::pair{"phases.close", p.close}, {"phases.settle", p.settle}, {"phases.hold", p.hold},
                         {"phases.lift", p.lift}, {"phases.hold_lifted", p.hold_lifted}}) {
    if (auto s = positive(name, v); !s.ok()) return s;
  }
  if (!(p.place >= 0 && std::isfinite(p.place))) return bad("phases.place", absl::StrFormat("must be >= 0, got %g", p.place));
  if (!(c.lift_height >= 0 && c.lift_height <= 0.5))
    return bad("lift_height", absl::StrFormat("must be in [0, 0.5] m, got %g", c.lift_height));
  if (!(c.pivot_angle_deg >= 0 && c.pivot_angle_deg <= 40))
    return bad("pivot_angle_deg", absl::StrFormat("must be in [0, 40], got %g", c.pivot_angle_deg));
  if (auto s = positive("control_rate", c.control_rate); !s.ok()) return s;
  if (auto s = ValidatePhysics(c.physics); !s.ok()) return s;
  if (c.control_rate * c.physics.timestep > 1.0 + 1e-9)
    return bad("control_rate", absl::StrFormat("%g Hz is faster than the physics (timestep %g s)", c.control_rate,
                                               c.physics.timestep));
  if (!(c.admittance_gain > 0 && c.admittance_gain <= 1))
    return bad("admittance_gain", absl::StrFormat("must be in (0, 1], got %g", c.admittance_gain));
  if (auto s = positive("kp", c.kp); !s.ok()) return s;
  if (auto s = positive("damping_ratio", c.damping_ratio); !s.ok()) return s;
  if (auto s = positive("fingertip_mass", c.fingertip_mass); !s.ok()) return s;
  if (std::sqrt(c.kp / c.fingertip_mass) * c.physics.timestep > 1.0)
    return bad("kp", absl::StrFormat("too stiff for fingertip_mass %g kg at timestep %g s (sqrt(kp/m) dt = %.2f > 1: "
                                     "the explicit PD would be unstable)",
                                     c.fingertip_mass, c.physics.timestep,
                                     std::sqrt(c.kp / c.fingertip_mass) * c.physics.timestep));
  if (!(c.fingertip_radius >= 0.003 && c.fingertip_radius <= 0.03))
    return bad("fingertip_radius", absl::StrFormat("must be in [0.003, 0.03] m, got %g", c.fingertip_radius));
  if (!(c.confidence >= 0 && std::isfinite(c.confidence)))
    return bad("confidence", absl::StrFormat("must be >= 0, got %g", c.confidence));
  if (auto s = positive("max_rotation_deg", c.max_rotation_deg); !s.ok()) return s;
  if (auto s = positive("max_slip", c.max_slip); !s.ok()) return s;
  if (!(c.drop_distance > c.max_slip))
    return bad("drop_distance", absl::StrFormat("must exceed max_slip (%g m), got %g", c.max_slip, c.drop_distance));
  if (c.sensors == SensorMode::kGeoDexRandom) {
    if (auto s = ValidateErrorRanges(c.error_ranges, "error_ranges."); !s.ok()) return s;
  }
  if (c.sensors == SensorMode::kModel) {
    if (auto s = sim::ValidateSensorModel(c.sensor_model); !s.ok())
      return absl::InvalidArgumentError(absl::StrCat("sensor_model.", s.message()));
    if (c.sensor_model.gain == 0) return bad("sensor_model.gain", "must not be 0");
  }
  return absl::OkStatus();
}

// ---------------------------------------------------------------------------

namespace {

// Minimum-jerk profile s(tau), tau in [0, 1], and its derivatives w.r.t. tau.
void MinJerk(double tau, double* s, double* ds, double* dds) {
  tau = std::clamp(tau, 0.0, 1.0);
  const double t2 = tau * tau, t3 = t2 * tau;
  *s = t3 * (10 - 15 * tau + 6 * t2);
  *ds = 30 * t2 * (1 - 2 * tau + t2);
  *dds = 60 * tau - 180 * t2 + 120 * t3;
}

Matrix3d RotX(double a) { return Eigen::AngleAxisd(a, Vec3::UnitX()).toRotationMatrix(); }

struct Timeline {
  double t_settle, t_hold, t_lift, t_hold_lifted, t_place, t_end;
  explicit Timeline(const PhaseDurations& p) {
    t_settle = p.close;
    t_hold = t_settle + p.settle;
    t_lift = t_hold + p.hold;
    t_hold_lifted = t_lift + p.lift;
    t_place = t_hold_lifted + p.hold_lifted;
    t_end = t_place + p.place;
  }
  Phase At(double t) const {
    if (t < t_settle) return Phase::kClose;
    if (t < t_hold) return Phase::kSettle;
    if (t < t_lift) return Phase::kHold;
    if (t < t_hold_lifted) return Phase::kLift;
    if (t < t_place) return Phase::kHoldLifted;
    return Phase::kPlace;
  }
};

// The hand's rigid motion relative to its pose at rest (identity before the lift).
struct HandMotion {
  Matrix3d R = Matrix3d::Identity();
  Vec3 p = Vec3::Zero();    // x_world = R (x0 - pivot) + pivot + p
  Vec3 v = Vec3::Zero();    // translation velocity
  Vec3 a = Vec3::Zero();
  Vec3 w = Vec3::Zero();    // angular velocity (world)
  Vec3 dw = Vec3::Zero();
};

}  // namespace

struct GraspSetup::Impl {
  std::vector<std::string> finger_names;
  planner::PlanProblem base;        // object frame, intrinsic contacts first
  planner::Inertia inertia;
  int n_fingers = 0;
  Vec3 rest_origin = Vec3::Zero();  // object origin (world) at rest
  bool pivot = false;               // cube: rotate about `pivot_point` around +x
  Vec3 pivot_point = Vec3::Zero();  // world
  double amplitude = 0;             // m (lift) or rad (pivot)
  Timeline timeline{PhaseDurations{}};
  int ticks = 0;
  std::vector<planner::PlanProblem> tick_problem;  // per control tick (estimation)
  std::vector<std::vector<double>> tick_desired;   // per tick, per finger (N)
  std::vector<std::vector<Vec3>> tick_force;       // per tick, per finger, object frame (N)

  HandMotion Motion(double t) const {
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
      h.R = RotX(th);
      h.w = Vec3(om, 0, 0);
      h.dw = Vec3(al, 0, 0);
    } else {
      h.p = Vec3(0, 0, amplitude * phi);
      h.v = Vec3(0, 0, amplitude * dphi);
      h.a = Vec3(0, 0, amplitude * ddphi);
    }
    return h;
  }
  // Where the hand moves a world point that was at x0 at rest, and its velocity.
  Vec3 Apply(const HandMotion& h, const Vec3& x0) const {
    return h.R * (x0 - pivot_point) + pivot_point + h.p;
  }
  Vec3 Velocity(const HandMotion& h, const Vec3& x0) const {
    return h.w.cross(h.R * (x0 - pivot_point)) + h.v;
  }
  Vec3 Acceleration(const HandMotion& h, const Vec3& x0) const {
    const Vec3 r = h.R * (x0 - pivot_point);
    return h.dw.cross(r) + h.w.cross(h.w.cross(r)) + h.a;
  }
  PhaseDurations phases;
};

GraspSetup::~GraspSetup() = default;
const std::vector<std::string>& GraspSetup::finger_names() const { return impl_->finger_names; }

namespace {

planner::Contact TableContact(const std::string& name, const Vec3& position, double mu) {
  planner::Contact c;
  c.name = name;
  c.position = position;
  c.normal = Vec3::UnitZ();
  c.friction = mu;
  c.kind = planner::ContactKind::kExtrinsic;
  return c;
}

std::string V3(const Vec3& v) { return absl::StrFormat("%.9g %.9g %.9g", v.x(), v.y(), v.z()); }

// Object geometry (body frame = object frame) as MJCF geoms, plus its pose.
struct ObjectMjcf {
  std::vector<std::string> geoms;  // each a complete <geom .../> without contype
  std::string inertial;
  double table_mu = 0.6;
};

}  // namespace

absl::StatusOr<std::unique_ptr<GraspSetup>> GraspSetup::Create(const GraspConfig& config) {
  if (absl::Status s = ValidateGraspConfig(config); !s.ok()) return s;
  std::unique_ptr<GraspSetup> setup(new GraspSetup());
  setup->config_ = config;
  setup->impl_ = std::make_unique<Impl>();
  Impl& im = *setup->impl_;
  im.phases = config.phases;
  im.timeline = Timeline(config.phases);
  planner::PlanOptions plan_options;
  ObjectMjcf obj;
  const double pi = std::numbers::pi;

  auto builtin = [&](const char* name) -> absl::StatusOr<planner::ExampleGrasp> {
    for (const planner::ExampleGrasp& g : planner::BuiltInGrasps())
      if (g.name == name) return g;
    return absl::InternalError(absl::StrCat("built-in grasp '", name, "' missing"));
  };

  switch (config.object) {
    case GraspObject::kSphere: {
      auto g = builtin("sphere-pinch");
      if (!g.ok()) return g.status();
      im.base = g->problem;
      plan_options = g->options;
      const double r = 0.035, m = im.base.object.mass;
      const double I = 0.4 * m * r * r;
      im.inertia = {I, I, I, 0, 0, 0};
      im.rest_origin = Vec3(0, 0, r);
      obj.geoms = {absl::StrFormat("<geom name=\"obj0\" type=\"sphere\" size=\"%g\" rgba=\"0.8 0.3 0.3 1\"/>", r)};
      break;
    }
    case GraspObject::kWrench: {
      auto g = builtin("wrench-3f");
      if (!g.ok()) return g.status();
      im.base = g->problem;
      plan_options = g->options;
      const planner::TrajectoryProblem t = planner::WrenchLiftAndRotate(2);
      im.inertia = *t.inertia;
      im.rest_origin = Vec3(0, 0, 0.008);
      // Handle 18 cm x 24 mm x 16 mm along x, a head at +x.
      obj.geoms = {
          "<geom name=\"obj0\" type=\"box\" size=\"0.09 0.012 0.008\" rgba=\"0.6 0.6 0.7 1\"/>",
          "<geom name=\"obj1\" type=\"box\" pos=\"0.11 0 0\" size=\"0.025 0.03 0.008\" rgba=\"0.6 0.6 0.7 1\"/>"};
      break;
    }
    case GraspObject::kCylinder: {
      auto g = builtin("cylinder-4f");
      if (!g.ok()) return g.status();
      im.base = g->problem;
      plan_options = g->options;
      const double r = 0.055, h = 0.12, m = im.base.object.mass;
      const double ixx = m * (3 * r * r + h * h) / 12, izz = 0.5 * m * r * r;
      im.inertia = {ixx, ixx, izz, 0, 0, 0};
      im.rest_origin = Vec3(0, 0, h / 2);
      obj.geoms = {absl::StrFormat("<geom name=\"obj0\" type=\"cylinder\" size=\"%g %g\" rgba=\"0.3 0.6 0.3 1\"/>",
                                   r, h / 2)};
      break;
    }
    case GraspObject::kCube: {
      const double a = 0.04, m = 0.15;  // half edge
      im.base.object.mass = m;
      auto finger = [](const char* name, const Vec3& p, const Vec3& n) {
        planner::Contact c;
        c.name = name;
        c.position = p;
        c.normal = n;
        c.friction = 0.8;
        c.kind = planner::ContactKind::kIntrinsic;
        c.sigma = 0.3;
        c.min_normal_force = 0.3;
        return c;
      };
      // Two fingertips on the +-x faces, above the centre and towards +y (the
      // side that rises); the cube pivots about its bottom edge at y = -a.
      im.base.contacts = {finger("thumb", Vec3(-a, 0.02, 0.02), Vec3::UnitX()),
                          finger("index", Vec3(a, 0.02, 0.02), -Vec3::UnitX()),
                          TableContact("edge-left", Vec3(-a, -a, -a), 0.6),
                          TableContact("edge-right", Vec3(a, -a, -a), 0.6)};
      const double I = m * (2 * a) * (2 * a) / 6;
      im.inertia = {I, I, I, 0, 0, 0};
      im.rest_origin = Vec3(0, 0, a);
      im.pivot = true;
      im.pivot_point = Vec3(0, -a, 0);
      obj.geoms = {absl::StrFormat("<geom name=\"obj0\" type=\"box\" size=\"%g %g %g\" rgba=\"0.3 0.3 0.8 1\"/>", a,
                                   a, a)};
      break;
    }
  }
  plan_options.confidence = config.confidence;
  im.amplitude = im.pivot ? config.pivot_angle_deg * pi / 180 : config.lift_height;
  for (const planner::Contact& c : im.base.contacts)
    if (c.kind == planner::ContactKind::kIntrinsic) {
      ++im.n_fingers;
      im.finger_names.push_back(c.name);
    }
  obj.inertial = absl::StrFormat(
      "<inertial pos=\"%s\" mass=\"%.9g\" fullinertia=\"%.9g %.9g %.9g %.9g %.9g %.9g\"/>", V3(im.base.object.com),
      im.base.object.mass, im.inertia.ixx, im.inertia.iyy, im.inertia.izz, im.inertia.ixy, im.inertia.ixz,
      im.inertia.iyz);

  // ---- force plans, one per control tick (Newton-Euler wrench of the motion)
  const double dt_tick = 1.0 / config.control_rate;
  im.ticks = static_cast<int>(std::ceil(im.timeline.t_end / dt_tick)) + 1;
  planner::TrajectoryProblem traj;
  traj.base = im.base;
  traj.inertia = im.inertia;
  for (int j = 0; j < im.ticks; ++j) {
    const double t = j * dt_tick;
    const HandMotion h = im.Motion(t);
    planner::TrajectoryStep step;
    const Matrix3d Rt = h.R.transpose();  // object axes = hand axes (aligned at rest)
    step.gravity = Rt * Vec3(0, 0, -9.81);
    step.linear_acceleration = Rt * im.Acceleration(h, im.rest_origin);
    step.angular_velocity = Rt * h.w;
    step.angular_acceleration = Rt * h.dw;
    if (im.pivot) {
      std::vector<planner::Contact> contacts = im.base.contacts;
      for (planner::Contact& c : contacts)
        if (c.kind == planner::ContactKind::kExtrinsic) c.normal = Rt * Vec3::UnitZ();
      step.contacts = contacts;
    }
    traj.steps.push_back(step);
  }
  auto planned = planner::PlanTrajectory(traj, plan_options, planner::SolverKind::kGeometric, true);
  if (!planned.ok()) return absl::InternalError(absl::StrCat("planner: ", planned.status().message()));
  for (int j = 0; j < im.ticks; ++j) {
    const planner::PlanResult& r = planned->steps[j];
    if (r.status != planner::PlanStatus::kOptimal)
      return absl::FailedPreconditionError(absl::StrFormat(
          "planner: step %d (t = %.3f s) of the %s grasp is %s: %s", j, j * dt_tick, ToString(config.object),
          planner::ToString(r.status), r.message));
    std::vector<double> fd;
    std::vector<Vec3> ff;
    for (int i = 0; i < im.n_fingers; ++i) fd.push_back(r.normal_forces[i]), ff.push_back(r.forces[i]);
    im.tick_desired.push_back(fd);
    im.tick_force.push_back(ff);
    im.tick_problem.push_back(planner::StepProblem(traj, j));
  }

  // ---- MJCF
  const PhysicsSettings& ph = config.physics;
  const double rf = config.fingertip_radius;
  std::string x = "<mujoco model=\"tactforce_grasp\">\n";
  absl::StrAppend(&x, OptionMjcf(ph));
  absl::StrAppend(&x, "<worldbody>\n<geom name=\"table\" type=\"plane\" size=\"0.5 0.5 0.01\" contype=\"0\" conaffinity=\"0\"/>\n");
  absl::StrAppend(&x, absl::StrFormat("<body name=\"object\" pos=\"%s\">\n<joint name=\"object_free\" type=\"free\"/>\n%s\n",
                                      V3(im.rest_origin), obj.inertial));
  for (const std::string& g : obj.geoms) {
    std::string gg = g;
    gg.insert(gg.size() - 2, " contype=\"0\" conaffinity=\"0\" mass=\"0\"");
    absl::StrAppend(&x, gg, "\n");
  }
  absl::StrAppend(&x, "</body>\n");
  for (int i = 0; i < im.n_fingers; ++i) {
    const planner::Contact& c = im.base.contacts[i];
    const Vec3 n = c.normal.normalized();
    const Vec3 open = im.rest_origin + c.position - n * (rf + 0.015);
    absl::StrAppend(&x, absl::StrFormat(
        "<body name=\"f%d\" pos=\"%s\">\n"
        "<joint name=\"f%dx\" type=\"slide\" axis=\"1 0 0\"/><joint name=\"f%dy\" type=\"slide\" axis=\"0 1 0\"/>"
        "<joint name=\"f%dz\" type=\"slide\" axis=\"0 0 1\"/>\n"
        "<geom name=\"f%dg\" type=\"sphere\" size=\"%.9g\" mass=\"%.9g\" contype=\"0\" conaffinity=\"0\" "
        "rgba=\"0.9 0.8 0.2 1\"/>\n</body>\n",
        i, V3(open), i, i, i, i, rf, config.fingertip_mass));
  }
  absl::StrAppend(&x, "</worldbody>\n<contact>\n");
  const std::string sol = SolrefAttr(ph);
  for (size_t g = 0; g < obj.geoms.size(); ++g) {
    for (int i = 0; i < im.n_fingers; ++i) {
      const double mu = im.base.contacts[i].friction;
      absl::StrAppend(&x, absl::StrFormat(
          "<pair geom1=\"f%dg\" geom2=\"obj%d\" condim=\"%d\" friction=\"%.9g %.9g %.9g 0.0001 0.0001\" %s/>\n", i, g,
          ph.condim_fingertip, mu, mu, ph.torsional_friction, sol));
    }
    absl::StrAppend(&x, absl::StrFormat(
        "<pair geom1=\"obj%d\" geom2=\"table\" condim=\"3\" friction=\"%.9g %.9g 0.005 0.0001 0.0001\" %s/>\n", g,
        obj.table_mu, obj.table_mu, sol));
  }
  absl::StrAppend(&x, "</contact>\n</mujoco>\n");
  setup->mjcf_ = std::move(x);
  // Compile once here so model errors surface at set-up.
  auto scene = Scene::FromMjcf(setup->mjcf_);
  if (!scene.ok()) return scene.status();
  return setup;
}

// ---------------------------------------------------------------------------

namespace {

uint64_t SplitMix(uint64_t x) {
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

struct FingerContact {
  double normal = 0, shear = 0;  // N (contact-frame magnitudes, summed)
};

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

}  // namespace

absl::StatusOr<TrialResult> RunGraspTrial(const GraspSetup& setup, int trial) {
  const auto wall0 = std::chrono::steady_clock::now();
  const GraspConfig& cfg = setup.config();
  const GraspSetup::Impl& im = setup.impl();
  if (trial < 0) return absl::InvalidArgumentError(absl::StrFormat("trial: must be >= 0, got %d", trial));
  auto scene_or = Scene::FromMjcf(setup.mjcf());
  if (!scene_or.ok()) return scene_or.status();
  Scene& sc = **scene_or;
  mjModel* m = sc.m;
  mjData* d = sc.d;
  const int nf = im.n_fingers;

  TrialResult res;
  res.trial = trial;
  res.seed = SplitMix(cfg.seed * 0x100000001b3ULL + static_cast<uint64_t>(trial));
  std::mt19937_64 rng(res.seed);

  // Sensors: same draws for either feedback mode.
  std::vector<SensorChannel> channels;
  for (int i = 0; i < nf; ++i) {
    sim::SensorModel model;
    if (cfg.sensors == SensorMode::kGeoDexRandom) model = DrawGeoDexModel(cfg.error_ranges, rng);
    else if (cfg.sensors == SensorMode::kModel) model = cfg.sensor_model;
    auto ch = SensorChannel::Create(model, SplitMix(res.seed + 17 * (i + 1)));
    if (!ch.ok()) return ch.status();
    channels.push_back(std::move(*ch));
    res.sensor_models.push_back(model);
  }

  const int object_body = sc.Body("object");
  std::vector<int> finger_geom(nf), dof(nf), qadr(nf);
  std::vector<Vec3> open(nf), center(nf), normal(nf);
  std::vector<double> delta(nf);
  std::vector<Vec3> offset(nf);  // target - contact-touching centre (hand frame)
  for (int i = 0; i < nf; ++i) {
    finger_geom[i] = sc.Geom(absl::StrCat("f", i, "g").c_str());
    const int jx = sc.Joint(absl::StrCat("f", i, "x").c_str());
    dof[i] = m->jnt_dofadr[jx];
    qadr[i] = m->jnt_qposadr[jx];
    const planner::Contact& c = im.base.contacts[i];
    normal[i] = c.normal.normalized();
    center[i] = im.rest_origin + c.position - normal[i] * cfg.fingertip_radius;
    open[i] = center[i] - normal[i] * 0.015;
    delta[i] = im.tick_desired[0][i] / cfg.kp;
    offset[i] = im.tick_force[0][i] / cfg.kp;
  }
  const int obj_q = m->jnt_qposadr[sc.Joint("object_free")];

  const double dt = m->opt.timestep;
  const int steps_per_tick = std::max(1, static_cast<int>(std::lround(1.0 / (cfg.control_rate * dt))));
  const int total_steps = static_cast<int>(std::ceil(im.timeline.t_end / dt));
  const double kd = 2 * cfg.damping_ratio * std::sqrt(cfg.kp * cfg.fingertip_mass);
  const double max_step = 0.001;  // m per tick

  estimator::EstimateOptions est_opt;
  est_opt.method = cfg.estimator;

  std::vector<double> raw(nf), est(nf), truth(nf), observed(nf), shear(nf);
  std::vector<Vec3> observed_force(nf);
  double err_sum = 0, fb_sum = 0;
  long err_n = 0;
  double ok_since = -1;
  bool lift_started = false;
  Vec3 p_lift = Vec3::Zero();
  Matrix3d R_lift = Matrix3d::Identity();
  bool dropped = false;

  for (int k = 0; k <= total_steps && !dropped; ++k) {
    const double t = k * dt;
    const Phase phase = im.timeline.At(t);
    const HandMotion hm = im.Motion(t);
    if (k % steps_per_tick == 0) {
      const int j = std::min(im.ticks - 1, static_cast<int>(std::lround(t * cfg.control_rate)));
      const std::vector<double>& desired = im.tick_desired[j];
      const std::vector<Vec3>& desired_force = im.tick_force[j];  // object frame = hand frame
      for (int i = 0; i < nf; ++i) {
        const FingerContact fc = MeasureFinger(m, d, finger_geom[i], object_body);
        truth[i] = fc.normal;
        shear[i] = fc.shear;
        raw[i] = channels[i].Step(t, fc.normal, fc.shear) / channels[i].model().gain;
      }
      auto e = estimator::EstimateForces(im.tick_problem[j], raw, est_opt);
      const bool est_ok = e.ok() && e->status == estimator::EstimateStatus::kOk;
      for (int i = 0; i < nf; ++i) est[i] = est_ok ? e->normal_forces[i] : raw[i];
      if (!est_ok && phase != Phase::kClose) ++res.estimate_failures;
      observed = cfg.feedback == Feedback::kRaw ? raw : est;
      for (int i = 0; i < nf; ++i)
        observed_force[i] = cfg.feedback == Feedback::kRaw || !est_ok ? Vec3(raw[i] * normal[i]) : e->forces[i];

      if (phase != Phase::kClose) {
        for (int i = 0; i < nf; ++i) {
          if (cfg.admittance == Admittance::kFull) {
            Vec3 step = cfg.admittance_gain * (desired_force[i] - observed_force[i]) / cfg.kp;
            if (step.norm() > max_step) step *= max_step / step.norm();
            offset[i] += step;
            if (offset[i].norm() > 0.03) offset[i] *= 0.03 / offset[i].norm();
          } else {
            const double step =
                std::clamp(cfg.admittance_gain * (desired[i] - observed[i]) / cfg.kp, -max_step, max_step);
            delta[i] = std::clamp(delta[i] + step, -0.01, 0.03);
            const Vec3& f = desired_force[i];
            offset[i] = normal[i] * delta[i] + (f - normal[i] * normal[i].dot(f)) / cfg.kp;
          }
        }
        // Convergence of the loop's own error (settle and hold).
        if (phase == Phase::kSettle || phase == Phase::kHold) {
          bool ok = true;
          for (int i = 0; i < nf; ++i)
            ok = ok && std::abs(desired[i] - observed[i]) < std::max(0.1, 0.1 * desired[i]);
          if (!ok) ok_since = -1;
          else if (ok_since < 0) ok_since = t;
          if (ok && res.converge_time < 0 && t - ok_since >= 0.1 - 1e-9)
            res.converge_time = ok_since - im.timeline.t_settle;
        }
      }
      if (phase == Phase::kHold || phase == Phase::kLift || phase == Phase::kHoldLifted) {
        for (int i = 0; i < nf; ++i) {
          err_sum += std::abs(truth[i] - desired[i]);
          fb_sum += std::abs(observed[i] - truth[i]);
        }
        ++err_n;
      }
      // Object pose versus where the hand holds it.
      const Vec3 p(d->qpos[obj_q], d->qpos[obj_q + 1], d->qpos[obj_q + 2]);
      const Eigen::Quaterniond q(d->qpos[obj_q + 3], d->qpos[obj_q + 4], d->qpos[obj_q + 5], d->qpos[obj_q + 6]);
      const Matrix3d R = q.toRotationMatrix();
      double slip = 0, rot = 0;
      if (phase == Phase::kLift || phase == Phase::kHoldLifted) {
        if (!lift_started) {
          lift_started = true;
          p_lift = p;
          R_lift = R;
        }
        // Expected pose: the hand's motion since the lift started applied to
        // the object's pose then (the hand is at rest when the lift starts).
        const Vec3 p_exp = im.Apply(hm, p_lift);
        const Matrix3d R_exp = hm.R * R_lift;
        slip = (p - p_exp).norm();
        rot = AngleDeg(R * R_exp.transpose());
        res.max_slip = std::max(res.max_slip, slip);
        res.max_rotation_deg = std::max(res.max_rotation_deg, rot);
        if (slip > cfg.drop_distance) dropped = true;
      }
      if (trial < cfg.trace_trials) {
        TraceSample s;
        s.t = t;
        s.phase = phase;
        s.desired = desired;
        s.raw = raw;
        s.estimated = est;
        s.truth = truth;
        s.slip = slip;
        s.rotation_deg = rot;
        res.trace.push_back(std::move(s));
      }
    }
    // Fingertip PD in fingertip space (J = I), gravity compensated.
    for (int i = 0; i < nf; ++i) {
      Vec3 target, vtarget = Vec3::Zero();
      if (phase == Phase::kClose) {
        double s, ds, dds;
        MinJerk(t / cfg.phases.close, &s, &ds, &dds);
        const Vec3 goal = center[i] + offset[i];
        target = open[i] + s * (goal - open[i]);
        vtarget = ds / cfg.phases.close * (goal - open[i]);
      } else {
        const Vec3 x0 = center[i] + offset[i];
        target = im.Apply(hm, x0);
        vtarget = im.Velocity(hm, x0);
      }
      for (int a = 0; a < 3; ++a) {
        const double x = open[i][a] + d->qpos[qadr[i] + a];
        const double v = d->qvel[dof[i] + a];
        d->qfrc_applied[dof[i] + a] =
            cfg.kp * (target[a] - x) + kd * (vtarget[a] - v) + (a == 2 ? cfg.fingertip_mass * 9.81 : 0.0);
      }
    }
    mj_step(m, d);
    if (!std::isfinite(d->qpos[obj_q])) return absl::InternalError("mujoco: simulation diverged");
  }
  res.dropped = dropped;
  res.force_error = err_n > 0 ? err_sum / (err_n * nf) : 0;
  res.feedback_error = err_n > 0 ? fb_sum / (err_n * nf) : 0;
  if (dropped) res.failure = "dropped";
  else if (res.max_slip >= cfg.max_slip) res.failure = absl::StrFormat("slip %.1f mm", res.max_slip * 1e3);
  else if (res.max_rotation_deg >= cfg.max_rotation_deg)
    res.failure = absl::StrFormat("rotation %.2f deg", res.max_rotation_deg);
  res.success = res.failure.empty();
  res.sim_seconds = d->time;
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

io::SvgPlot TracePlot(const TrialResult& trial, const std::vector<std::string>& finger_names, const std::string& title) {
  io::SvgPlot plot;
  plot.title = title;
  plot.x_label = "time (s)";
  for (const TraceSample& s : trial.trace) plot.x.push_back(s.t);
  Phase last = Phase::kClose;
  for (size_t k = 0; k < trial.trace.size(); ++k) {
    const TraceSample& s = trial.trace[k];
    if (k == 0 || s.phase != last) plot.markers.emplace_back(s.t, ToString(s.phase));
    last = s.phase;
  }
  for (size_t i = 0; i < finger_names.size(); ++i) {
    io::SvgPanel panel;
    panel.title = absl::StrCat("fingertip ", finger_names[i], ": normal force");
    panel.y_label = "N";
    io::SvgSeries des{"desired", "#000000", true, {}}, est{"estimated", "#1f77b4", false, {}},
        raw{"raw reading", "#ff7f0e", false, {}}, tru{"true (MuJoCo)", "#2ca02c", false, {}};
    for (const TraceSample& s : trial.trace) {
      des.y.push_back(s.desired[i]);
      est.y.push_back(s.estimated[i]);
      raw.y.push_back(s.raw[i]);
      tru.y.push_back(s.truth[i]);
    }
    panel.series = {tru, raw, est, des};
    plot.panels.push_back(std::move(panel));
  }
  io::SvgPanel motion;
  motion.title = "object vs where the hand holds it (lift and hold)";
  motion.y_label = "mm, deg";
  io::SvgSeries slip{"slip (mm)", "#d62728", false, {}}, rot{"rotation (deg)", "#9467bd", false, {}};
  for (const TraceSample& s : trial.trace) {
    slip.y.push_back(s.slip * 1e3);
    rot.y.push_back(s.rotation_deg);
  }
  motion.series = {slip, rot};
  plot.panels.push_back(std::move(motion));
  return plot;
}

}  // namespace tactforce::experiment
