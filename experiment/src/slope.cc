// The slope method and the probe in MuJoCo (slope.h): a fingertip on a plate
// that a mocap body tilts slowly until the fingertip slides (mu_slope =
// tan(tilt)), then the same fingertip pushed along a level plate while its
// normal force ramps down, the contact forces going to EstimateFriction; and
// the creep a fingertip shows on a plate tilted inside its friction cone.
#include "tactforce/experiment/slope.h"

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "scene.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;

// A plate (mocap body, tilted about x through the origin; its top face at
// the body origin) and a fingertip on three world slide joints.
std::string PlateMjcf(const PhysicsSettings& p, double mu, double mass, double radius,
                      bool mocap_plate) {
  std::string x = "<mujoco model=\"tactforce_slope\">\n";
  absl::StrAppend(&x, OptionMjcf(p), "<worldbody>\n");
  absl::StrAppend(
      &x, absl::StrFormat(
              "<body name=\"plate\" %s>\n<geom name=\"plate\" type=\"box\" pos=\"0 0 -0.01\" "
              "size=\"0.3 0.3 0.01\" contype=\"0\" conaffinity=\"0\"/>\n</body>\n",
              mocap_plate ? "mocap=\"true\"" : ""));
  absl::StrAppend(
      &x,
      absl::StrFormat(
          "<body name=\"tip\" pos=\"0 0 %.9g\">\n<joint name=\"tx\" type=\"slide\" axis=\"1 0 0\"/>"
          "<joint name=\"ty\" type=\"slide\" axis=\"0 1 0\"/><joint name=\"tz\" type=\"slide\" "
          "axis=\"0 0 1\"/>\n"
          "<geom name=\"tip\" type=\"sphere\" size=\"%.9g\" mass=\"%.9g\" contype=\"0\" "
          "conaffinity=\"0\"/>\n</body>\n",
          radius, radius, mass));
  absl::StrAppend(
      &x,
      absl::StrFormat("</worldbody>\n<contact>\n<pair geom1=\"tip\" geom2=\"plate\" condim=\"3\" "
                      "friction=\"%.9g %.9g 0.005 0.0001 0.0001\" %s/>\n</contact>\n</mujoco>\n",
                      mu, mu, SolrefAttr(p)));
  return x;
}

void SetTilt(Scene& s, double theta) {
  Eigen::Quaterniond q(Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()));
  s.d->mocap_quat[0] = q.w();
  s.d->mocap_quat[1] = q.x();
  s.d->mocap_quat[2] = q.y();
  s.d->mocap_quat[3] = q.z();
}

// Fingertip centre (world) and its position along the plate's down-slope axis.
Eigen::Vector3d TipPos(const Scene& s, double radius) {
  return Eigen::Vector3d(s.d->qpos[0], s.d->qpos[1], s.d->qpos[2] + radius);
}
double AlongPlate(const Eigen::Vector3d& p, double theta) {
  // Plate y axis in world: (0, cos, sin); down-slope is -y_plate.
  return -(p.y() * std::cos(theta) + p.z() * std::sin(theta));
}

// Place the tip resting on a plate at tilt theta (centre at R(theta) (0,0,r)).
void PlaceTip(Scene& s, double theta, double radius) {
  const Eigen::Vector3d c =
      Eigen::AngleAxisd(theta, Eigen::Vector3d::UnitX()) * Eigen::Vector3d(0, 0, radius);
  s.d->qpos[0] = c.x();
  s.d->qpos[1] = c.y();
  s.d->qpos[2] = c.z() - radius;
  SetTilt(s, theta);
  mj_forward(s.m, s.d);
}

// Slope: the tilt (rad) at which the fingertip has slid `slip_distance`.
absl::StatusOr<double> SlipTilt(const SlopeConfig& c, double mu) {
  const double r = c.fingertip_radius;
  TF_ASSIGN_OR_RETURN(auto sc,
                      Scene::FromMjcf(PlateMjcf(c.physics, mu, c.fingertip_mass, r, true)));
  Scene& s = *sc;
  const double theta0 = std::max(0.0, std::atan(mu) - c.start_margin_deg * kDeg);
  PlaceTip(s, theta0, r);
  const double dt = s.m->opt.timestep;
  for (double t = 0; t < c.settle; t += dt) mj_step(s.m, s.d);
  const double start = AlongPlate(TipPos(s, r), theta0);
  const double rate = c.tilt_rate_deg * kDeg;
  const double theta_max = std::atan(mu) + 10 * kDeg;
  double theta = theta0;
  for (double t = 0; theta < theta_max; t += dt) {
    theta = theta0 + rate * t;
    SetTilt(s, theta);
    mj_step(s.m, s.d);
    if (AlongPlate(TipPos(s, r), theta) - start > c.slip_distance) return theta;
  }
  return absl::InternalError(
      absl::StrFormat("slope: no slip up to %.1f deg at mu %g", theta_max / kDeg, mu));
}

// Probe: the contact force and point, sampled at `sample_rate` after the
// settle, while the normal force ramps down at `probe_ramp` under a constant
// tangential force; until 0.3 s after the slip or the normal force is gone.
absl::StatusOr<estimator::FrictionTrial> ProbeTrial(const SlopeConfig& c, double mu) {
  TF_ASSIGN_OR_RETURN(auto sc, Scene::FromMjcf(PlateMjcf(c.physics, mu, c.fingertip_mass,
                                                         c.fingertip_radius, false)));
  Scene& s = *sc;
  mj_forward(s.m, s.d);
  const int plate = s.Geom("plate"), tip = s.Geom("tip");
  const double dt = s.m->opt.timestep;
  const double ft = c.probe_tangential;
  const double fn0 = c.probe_start_ratio * ft / mu;
  const double settle = 0.3;
  const int every = std::max(1, static_cast<int>(std::lround(1.0 / (c.sample_rate * dt))));
  estimator::FrictionTrial trial;
  trial.name = absl::StrFormat("mujoco mu %g", mu);
  trial.normal = Eigen::Vector3d(0, 0, -1);
  double slip_at = -1;
  const double t_end = settle + fn0 / c.probe_ramp;
  for (int k = 0;; ++k) {
    const double t = k * dt;
    if (t > t_end || (slip_at >= 0 && t > slip_at + 0.3)) break;
    // Normal force: ramp in over the settle time, then down at `probe_ramp`.
    const double fn =
        t < settle ? fn0 * t / settle : std::max(0.0, fn0 - c.probe_ramp * (t - settle));
    const double tangential = t < settle ? ft * t / settle : ft;
    s.d->qfrc_applied[0] = tangential;
    s.d->qfrc_applied[1] = 0;
    s.d->qfrc_applied[2] = -fn + c.fingertip_mass * 9.81;
    mj_step(s.m, s.d);
    if (slip_at < 0 && std::abs(s.d->qpos[0]) > 0.005) slip_at = t;
    if (t >= settle && k % every == 0) {
      double f[3], p[3];
      if (PairForce(s.m, s.d, plate, tip, f, p) == 0) continue;
      estimator::FrictionSample smp;
      smp.t = t - settle;
      smp.force = Eigen::Vector3d(f[0], f[1], f[2]);
      smp.contact_point = Eigen::Vector3d(p[0], p[1], p[2]);
      trial.samples.push_back(smp);
    }
  }
  return trial;
}

}  // namespace

absl::Status ValidateSlopeConfig(const SlopeConfig& c) {
  auto bad = [](const std::string& f, const std::string& why) {
    return absl::InvalidArgumentError(absl::StrCat(f, ": ", why));
  };
  if (c.mus.empty()) return bad("mus", "empty");
  for (size_t i = 0; i < c.mus.size(); ++i)
    if (!(c.mus[i] > 0.02 && c.mus[i] <= 2))
      return bad(absl::StrCat("mus[", i, "]"),
                 absl::StrFormat("must be in (0.02, 2], got %g", c.mus[i]));
  if (!(c.fingertip_mass > 0)) return bad("fingertip_mass", "must be > 0");
  if (!(c.fingertip_radius > 0.002 && c.fingertip_radius < 0.05))
    return bad("fingertip_radius", "must be in (0.002, 0.05) m");
  if (!(c.tilt_rate_deg > 0 && c.tilt_rate_deg <= 30))
    return bad("tilt_rate_deg", "must be in (0, 30]");
  if (!(c.start_margin_deg >= 0)) return bad("start_margin_deg", "must be >= 0");
  if (!(c.settle >= 0)) return bad("settle", "must be >= 0");
  if (!(c.slip_distance > 0)) return bad("slip_distance", "must be > 0");
  if (!(c.probe_tangential > 0)) return bad("probe_tangential", "must be > 0");
  if (!(c.probe_ramp > 0)) return bad("probe_ramp", "must be > 0");
  if (!(c.probe_start_ratio > 1)) return bad("probe_start_ratio", "must be > 1");
  if (!(c.sample_rate > 0)) return bad("sample_rate", "must be > 0");
  return ValidatePhysics(c.physics);
}

absl::StatusOr<SlopeRow> RunSlopeAndProbe(const SlopeConfig& c, double mu) {
  SlopeConfig one = c;
  one.mus = {mu};
  TF_RETURN_IF_ERROR(ValidateSlopeConfig(one));
  SlopeRow row;
  row.mu = mu;
  TF_ASSIGN_OR_RETURN(double theta, SlipTilt(c, mu));
  row.slip_tilt_deg = theta / kDeg;
  row.mu_slope = std::tan(theta);
  TF_ASSIGN_OR_RETURN(estimator::FrictionTrial trial, ProbeTrial(c, mu));
  TF_ASSIGN_OR_RETURN(auto est, estimator::EstimateFriction({trial}, c.friction));
  const estimator::TrialFriction& tr = est.trials[0];
  row.probe_valid = tr.valid && tr.slipped;
  row.mu_probe = tr.mu;
  row.probe_message = tr.message;
  return row;
}

absl::StatusOr<std::vector<SlopeRow>> RunSlopeTable(const SlopeConfig& c) {
  TF_RETURN_IF_ERROR(ValidateSlopeConfig(c));
  std::vector<SlopeRow> rows;
  for (double mu : c.mus) {
    TF_ASSIGN_OR_RETURN(auto r, RunSlopeAndProbe(c, mu));
    rows.push_back(r);
  }
  return rows;
}

absl::StatusOr<double> MeasureCreep(const PhysicsSettings& physics, double mu, double load_ratio,
                                    double seconds, double settle, double fingertip_mass) {
  TF_RETURN_IF_ERROR(ValidatePhysics(physics));
  if (!(load_ratio >= 0 && load_ratio < 1))
    return absl::InvalidArgumentError(
        absl::StrFormat("load_ratio: must be in [0, 1), got %g", load_ratio));
  if (!(mu > 0)) return absl::InvalidArgumentError("mu: must be > 0");
  const double r = 0.012;
  TF_ASSIGN_OR_RETURN(auto sc, Scene::FromMjcf(PlateMjcf(physics, mu, fingertip_mass, r, true)));
  Scene& s = *sc;
  const double theta = std::atan(load_ratio * mu);
  PlaceTip(s, theta, r);
  const double dt = s.m->opt.timestep;
  for (double t = 0; t < settle; t += dt) mj_step(s.m, s.d);
  const double x0 = AlongPlate(TipPos(s, r), theta);
  const int n = static_cast<int>(std::lround(seconds / dt));
  for (int k = 0; k < n; ++k) mj_step(s.m, s.d);
  return (AlongPlate(TipPos(s, r), theta) - x0) / (n * dt);
}

}  // namespace tactforce::experiment
