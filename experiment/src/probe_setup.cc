// One in-grasp probe trial's set-up (probe_internal.h): the three holding
// fingertips on the box's x faces, the probe on its top face (position
// jittered per trial), the PlanFrictionProbe holding plan (the probe's force
// is the external wrench; on a table the bottom corners are extrinsic
// contacts), and the MJCF scene: free box, four floating fingertips on slide
// joints, optional table, explicit contact pairs.
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "probe_internal.h"
#include "scene.h"
#include "tactforce/planner/solver.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

using planner::Vec3;

std::string V3(const Vec3& v) { return absl::StrFormat("%.9g %.9g %.9g", v.x(), v.y(), v.z()); }

planner::Contact Holding(const char* name, const Vec3& p, const Vec3& n, double mu,
                         const ProbeConfig& c) {
  planner::Contact k;
  k.name = name;
  k.position = p;
  k.normal = n;
  k.friction = mu;
  k.kind = planner::ContactKind::kIntrinsic;
  k.sigma = c.plan_sigma;
  k.min_normal_force = 0.3;
  return k;
}

// The holding problem: box mass and CoM, three fingertips, table corners.
// In the air the thumb opposes the probe from the bottom face (the probe's
// normal force goes straight into it, not through friction) and two fingers
// pinch the x faces; on a table, which carries the normal force, the thumb
// is on the -x face and the two fingers on the +x face.
planner::PlanProblem HoldingProblem(const ProbeConfig& c, double mu, const Vec3& probe,
                                    std::vector<planner::Contact>* fingers) {
  const Vec3 h = c.object.size / 2;
  fingers->clear();
  if (c.on_table) {
    fingers->push_back(Holding("thumb", Vec3(-h.x(), 0, 0), Vec3::UnitX(), mu, c));
    fingers->push_back(Holding("middle", Vec3(h.x(), 0.5 * h.y(), 0), -Vec3::UnitX(), mu, c));
    fingers->push_back(Holding("ring", Vec3(h.x(), -0.5 * h.y(), 0), -Vec3::UnitX(), mu, c));
  } else {
    fingers->push_back(Holding("thumb", Vec3(probe.x(), probe.y(), -h.z()), Vec3::UnitZ(), mu, c));
    fingers->push_back(Holding("middle", Vec3(h.x(), 0, 0), -Vec3::UnitX(), mu, c));
    fingers->push_back(Holding("ring", Vec3(-h.x(), 0, 0), Vec3::UnitX(), mu, c));
  }
  planner::PlanProblem p;
  p.object.mass = c.object.mass;
  p.object.com = c.object.com_offset;
  p.contacts = *fingers;
  if (c.on_table) {
    for (int k = 0; k < 4; ++k) {
      planner::Contact t;
      t.name = absl::StrCat("table", k);
      t.position = Vec3(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), -h.z());
      t.normal = Vec3::UnitZ();
      t.friction = c.table_mu;
      t.kind = planner::ContactKind::kExtrinsic;
      p.contacts.push_back(t);
    }
  }
  return p;
}

// Box inertia about its centre, moved to the CoM (parallel axis).
std::string BoxBodyMjcf(const ProbeConfig& c, const Vec3& rest) {
  const Vec3 s = c.object.size, r = c.object.com_offset;
  const double m = c.object.mass;
  Eigen::Matrix3d I = Eigen::Vector3d(s.y() * s.y() + s.z() * s.z(), s.x() * s.x() + s.z() * s.z(),
                                      s.x() * s.x() + s.y() * s.y())
                          .asDiagonal();
  I *= m / 12;
  I -= m * (r.squaredNorm() * Eigen::Matrix3d::Identity() - r * r.transpose());
  return absl::StrFormat(
      "<body name=\"object\" pos=\"%s\">\n<joint name=\"object_free\" type=\"free\"/>\n"
      "<inertial pos=\"%s\" mass=\"%.9g\" fullinertia=\"%.9g %.9g %.9g %.9g %.9g %.9g\"/>\n"
      "<geom name=\"box\" type=\"box\" size=\"%s\" contype=\"0\" conaffinity=\"0\" "
      "mass=\"0\"/>\n</body>\n",
      V3(rest), V3(r), m, I(0, 0), I(1, 1), I(2, 2), I(0, 1), I(0, 2), I(1, 2), V3(s / 2));
}

std::string TipMjcf(const std::string& name, const Vec3& center, const ProbeConfig& c) {
  return absl::StrFormat(
      "<body name=\"%s\" pos=\"%s\">\n<joint name=\"%sx\" type=\"slide\" axis=\"1 0 0\"/>"
      "<joint name=\"%sy\" type=\"slide\" axis=\"0 1 0\"/><joint name=\"%sz\" type=\"slide\" "
      "axis=\"0 0 1\"/>\n"
      "<geom name=\"%sg\" type=\"sphere\" size=\"%.9g\" mass=\"%.9g\" contype=\"0\" "
      "conaffinity=\"0\"/>\n</body>\n",
      name, V3(center), name, name, name, name, c.fingertip_radius, c.fingertip_mass);
}

// Fingertips f0..f2 start 15 mm back from their contacts; the probe "p"
// starts touching the top face. The probe pair is condim 3 like the slope
// method's plate, so both see the same Coulomb pair.
std::string ProbeMjcf(const ProbeConfig& c, const ProbeSetup& s, double mu) {
  const PhysicsSettings& ph = c.slope.physics;
  const double rf = c.fingertip_radius;
  std::string x =
      absl::StrCat("<mujoco model=\"tactforce_probe\">\n", OptionMjcf(ph), "<worldbody>\n");
  if (c.on_table)
    absl::StrAppend(&x,
                    "<geom name=\"table\" type=\"plane\" size=\"0.5 0.5 0.01\" contype=\"0\" "
                    "conaffinity=\"0\"/>\n");
  absl::StrAppend(&x, BoxBodyMjcf(c, s.rest_position));
  for (int i = 0; i < kHoldingFingers; ++i) {
    const planner::Contact& k = s.holding[i];
    absl::StrAppend(&x, TipMjcf(absl::StrCat("f", i),
                                s.rest_position + k.position - k.normal * (rf + 0.015), c));
  }
  absl::StrAppend(&x, TipMjcf("p", s.rest_position + s.probe.position + Vec3(0, 0, rf), c),
                  "</worldbody>\n<contact>\n");
  const std::string sol = SolrefAttr(ph);
  for (int i = 0; i < kHoldingFingers; ++i)
    absl::StrAppend(
        &x, absl::StrFormat("<pair geom1=\"f%dg\" geom2=\"box\" condim=\"%d\" friction=\"%.9g %.9g "
                            "%.9g 0.0001 0.0001\" %s/>\n",
                            i, ph.condim_fingertip, mu, mu, ph.torsional_friction, sol));
  absl::StrAppend(
      &x,
      absl::StrFormat("<pair geom1=\"pg\" geom2=\"box\" condim=\"3\" friction=\"%.9g %.9g 0.005 "
                      "0.0001 0.0001\" %s/>\n",
                      mu, mu, sol));
  if (c.on_table)
    absl::StrAppend(
        &x, absl::StrFormat(
                "<pair geom1=\"box\" geom2=\"table\" condim=\"3\" friction=\"%.9g %.9g 0.005 "
                "0.0001 0.0001\" %s/>\n",
                c.table_mu, c.table_mu, sol));
  absl::StrAppend(&x, "</contact>\n</mujoco>\n");
  return x;
}

}  // namespace

absl::StatusOr<ProbeSetup> MakeProbeSetup(const ProbeConfig& c, const SurfacePair& surface,
                                          std::mt19937_64& rng) {
  ProbeSetup s;
  const Vec3 h = c.object.size / 2;
  std::uniform_real_distribution<double> jitter(-1, 1);
  // Start a quarter of the face behind the centre so the probe has room to slide towards +x.
  s.probe.position =
      Vec3(-0.5 * h.x() + 0.2 * h.x() * jitter(rng), 0.3 * h.y() * jitter(rng), h.z());
  s.probe.normal = -Vec3::UnitZ();
  s.probe.tangent = Vec3::UnitX();
  s.probe.tangential_force = c.slope.probe_tangential;
  s.probe.initial_normal_force = c.slope.probe_start_ratio * c.slope.probe_tangential / surface.mu;
  // The schedule brackets the expected slip force (1 N / mu) by the same
  // factor on both sides: it starts start_ratio above and stops that far below.
  s.probe.final_normal_force = c.slope.probe_tangential / (c.slope.probe_start_ratio * surface.mu);
  s.probe.ramp_rate = c.slope.probe_ramp;
  s.probe.sample_rate = c.slope.sample_rate;
  const planner::PlanProblem holding = HoldingProblem(c, surface.mu, s.probe.position, &s.holding);
  planner::PlanOptions options;
  options.confidence = c.confidence;
  absl::StatusOr<planner::ProbePlan> plan =
      planner::PlanFrictionProbe(holding, s.probe, options, planner::SolverKind::kGeometric);
  if (!plan.ok()) return io::PrependPath(absl::InternalError(plan.status().message()), "planner");
  for (size_t k = 0; k < plan->holding.steps.size(); ++k)
    if (plan->holding.steps[k].status != planner::PlanStatus::kOptimal)
      return absl::FailedPreconditionError(absl::StrFormat(
          "planner: the holding grasp of %s at mu %g is %s at t = %.2f s: %s", c.object.name,
          surface.mu, planner::ToString(plan->holding.steps[k].status), plan->times[k],
          plan->holding.steps[k].message));
  s.plan = *std::move(plan);
  s.rest_position = Vec3(0, 0, c.on_table ? h.z() : 0.2);
  s.mjcf = ProbeMjcf(c, s, surface.mu);
  return s;
}

}  // namespace tactforce::experiment
