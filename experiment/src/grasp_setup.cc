// GraspSetup::Create: everything a grasp trial shares across trials. It looks
// the object up in the spec table (grasp_objects.h), fixes the hand's motion
// (lift, or the cube's pivot), plans the fingertip forces for every control
// tick with one warm-started trajectory plan (the Newton-Euler wrench of that
// motion; for the pivot the table normal and gravity turn in the object
// frame), and writes the MJCF scene: table, free object with explicit contact
// pairs, one floating sphere per fingertip on three slide joints.
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "grasp_internal.h"
#include "grasp_objects.h"
#include "scene.h"
#include "tactforce/planner/solver.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/sim/taxel_array.h"

namespace tactforce::experiment {
namespace {

using Eigen::Matrix3d;
using planner::Vec3;

std::string V3(const Vec3& v) { return absl::StrFormat("%.9g %.9g %.9g", v.x(), v.y(), v.z()); }

// The planner's view of the object: the truth, or the planning model's mass,
// CoM, inertia, uncertainty and fingertip friction in its place.
void ApplyPlanningModel(const std::optional<PlanningModel>& model, planner::PlanProblem* problem,
                        planner::Inertia* inertia) {
  if (!model.has_value()) return;
  problem->object.mass = model->mass;
  problem->object.com = model->com;
  problem->object.uncertainty = model->uncertainty;
  *inertia = model->inertia;
  for (planner::Contact& c : problem->contacts)
    if (c.kind == planner::ContactKind::kIntrinsic) {
      c.friction = model->friction;
      c.friction_sigma = model->friction_sigma;
    }
}

// The object (grasp problem, inertia, rest pose), the hand's motion (lift or
// pivot) and the fingers, from the spec; returns the plan options.
absl::StatusOr<planner::PlanOptions> SetUpObjectAndMotion(const GraspConfig& config,
                                                          const ObjectSpec& spec,
                                                          GraspSetup::Impl* im) {
  TF_ASSIGN_OR_RETURN(ObjectGrasp grasp, ResolveGrasp(spec));
  im->base = grasp.problem;
  im->inertia = spec.inertia(im->base.object.mass);
  im->plan_base = im->base;
  im->plan_inertia = im->inertia;
  ApplyPlanningModel(config.planning_model, &im->plan_base, &im->plan_inertia);
  im->rest_origin = spec.rest_origin;
  im->pivot = spec.pivot_point.has_value();
  if (im->pivot) im->pivot_point = *spec.pivot_point;
  im->phases = config.phases;
  im->timeline = Timeline(config.phases);
  im->amplitude = im->pivot ? config.pivot_angle_deg * std::numbers::pi / 180 : config.lift_height;
  for (const planner::Contact& c : im->base.contacts)
    if (c.kind == planner::ContactKind::kIntrinsic) {
      ++im->n_fingers;
      im->finger_names.push_back(c.name);
    }
  planner::PlanOptions options = grasp.options;
  options.confidence = config.confidence;
  return options;
}

// One trajectory step per control tick from `first` on: the wrench of the
// hand's motion in the (possibly rotating) object frame, on `base`'s contacts.
planner::TrajectoryProblem TickTrajectory(const GraspSetup::Impl& im, double dt_tick,
                                          const planner::PlanProblem& base, int first) {
  planner::TrajectoryProblem traj;
  traj.base = base;
  traj.inertia = im.plan_inertia;
  for (int j = first; j < im.ticks; ++j) {
    const HandMotion h = im.Motion(j * dt_tick);
    planner::TrajectoryStep step;
    const Matrix3d Rt = h.R.transpose();  // object axes = hand axes (aligned at rest)
    step.gravity = Rt * Vec3(0, 0, -9.81);
    step.linear_acceleration = Rt * im.Acceleration(h, im.rest_origin);
    step.angular_velocity = Rt * h.w;
    step.angular_acceleration = Rt * h.dw;
    if (im.pivot) {
      std::vector<planner::Contact> contacts = base.contacts;
      for (planner::Contact& c : contacts)
        if (c.kind == planner::ContactKind::kExtrinsic) c.normal = Rt * Vec3::UnitZ();
      step.contacts = contacts;
    }
    traj.steps.push_back(step);
  }
  return traj;
}

// Fills the per-tick desired forces and estimation problems.
absl::Status PlanTicks(const GraspConfig& config, const planner::PlanOptions& options,
                       GraspSetup::Impl* im) {
  const double dt_tick = 1.0 / config.control_rate;
  im->ticks = static_cast<int>(std::ceil(im->timeline.t_end / dt_tick)) + 1;
  const planner::TrajectoryProblem traj = TickTrajectory(*im, dt_tick, im->plan_base, 0);
  auto planned = planner::PlanTrajectory(traj, options, planner::SolverKind::kGeometric, true);
  if (!planned.ok())
    return io::PrependPath(absl::InternalError(planned.status().message()), "planner");
  for (int j = 0; j < im->ticks; ++j) {
    const planner::PlanResult& r = planned->steps[j];
    if (r.status != planner::PlanStatus::kOptimal)
      return absl::FailedPreconditionError(
          absl::StrFormat("planner: step %d (t = %.3f s) of the %s grasp is %s: %s", j, j * dt_tick,
                          ToString(config.object), planner::ToString(r.status), r.message));
    std::vector<double> fd;
    std::vector<Vec3> ff;
    for (int i = 0; i < im->n_fingers; ++i)
      fd.push_back(r.normal_forces[i]), ff.push_back(r.forces[i]);
    im->tick_desired.push_back(fd);
    im->tick_force.push_back(ff);
    im->tick_problem.push_back(planner::StepProblem(traj, j));
  }
  return absl::OkStatus();
}

// The free object body: inertial and its geoms (contacts only through pairs).
std::string ObjectBodyMjcf(const GraspSetup::Impl& im, const std::vector<std::string>& geoms) {
  const std::string inertial = absl::StrFormat(
      "<inertial pos=\"%s\" mass=\"%.9g\" fullinertia=\"%.9g %.9g %.9g %.9g %.9g %.9g\"/>",
      V3(im.base.object.com), im.base.object.mass, im.inertia.ixx, im.inertia.iyy, im.inertia.izz,
      im.inertia.ixy, im.inertia.ixz, im.inertia.iyz);
  std::string x = absl::StrFormat(
      "<body name=\"object\" pos=\"%s\">\n<joint name=\"object_free\" type=\"free\"/>\n%s\n",
      V3(im.rest_origin), inertial);
  for (const std::string& g : geoms) {
    std::string gg = g;
    gg.insert(gg.size() - 2, " contype=\"0\" conaffinity=\"0\" mass=\"0\"");
    absl::StrAppend(&x, gg, "\n");
  }
  absl::StrAppend(&x, "</body>\n");
  return x;
}

// Fingertip i: a sphere on three world slide joints, 15 mm off its contact.
std::string FingertipBodyMjcf(const GraspConfig& config, const GraspSetup::Impl& im, int i) {
  const double rf = config.fingertip_radius;
  const planner::Contact& c = im.base.contacts[i];
  const Vec3 n = c.normal.normalized();
  const Vec3 open = im.rest_origin + c.position - n * (rf + 0.015);
  return absl::StrFormat(
      "<body name=\"f%d\" pos=\"%s\">\n"
      "<joint name=\"f%dx\" type=\"slide\" axis=\"1 0 0\"/><joint name=\"f%dy\" type=\"slide\" "
      "axis=\"0 1 0\"/>"
      "<joint name=\"f%dz\" type=\"slide\" axis=\"0 0 1\"/>\n"
      "<geom name=\"f%dg\" type=\"sphere\" size=\"%.9g\" mass=\"%.9g\" contype=\"0\" "
      "conaffinity=\"0\" "
      "rgba=\"0.9 0.8 0.2 1\"/>\n</body>\n",
      i, V3(open), i, i, i, i, rf, config.fingertip_mass);
}

// Explicit contact pairs: every fingertip with every object geom (the
// planner's mu), every object geom with the table.
std::string ContactPairsMjcf(const GraspConfig& config, const GraspSetup::Impl& im, size_t n_geoms,
                             double table_mu) {
  const PhysicsSettings& ph = config.physics;
  const std::string sol = SolrefAttr(ph);
  std::string x = "<contact>\n";
  for (size_t g = 0; g < n_geoms; ++g) {
    for (int i = 0; i < im.n_fingers; ++i) {
      const double mu = im.base.contacts[i].friction;
      absl::StrAppend(
          &x, absl::StrFormat("<pair geom1=\"f%dg\" geom2=\"obj%d\" condim=\"%d\" friction=\"%.9g "
                              "%.9g %.9g 0.0001 0.0001\" %s/>\n",
                              i, g, ph.condim_fingertip, mu, mu, ph.torsional_friction, sol));
    }
    absl::StrAppend(&x, absl::StrFormat("<pair geom1=\"obj%d\" geom2=\"table\" condim=\"3\" "
                                        "friction=\"%.9g %.9g 0.005 0.0001 0.0001\" %s/>\n",
                                        g, table_mu, table_mu, sol));
  }
  absl::StrAppend(&x, "</contact>\n");
  return x;
}

std::string GraspMjcf(const GraspConfig& config, const ObjectSpec& spec,
                      const GraspSetup::Impl& im) {
  const std::vector<std::string> geoms = GeomElements(spec);
  std::string x = "<mujoco model=\"tactforce_grasp\">\n";
  absl::StrAppend(&x, OptionMjcf(config.physics));
  absl::StrAppend(&x,
                  "<worldbody>\n<geom name=\"table\" type=\"plane\" size=\"0.5 0.5 0.01\" "
                  "contype=\"0\" conaffinity=\"0\"/>\n");
  absl::StrAppend(&x, ObjectBodyMjcf(im, geoms));
  for (int i = 0; i < im.n_fingers; ++i) absl::StrAppend(&x, FingertipBodyMjcf(config, im, i));
  absl::StrAppend(&x, "</worldbody>\n", ContactPairsMjcf(config, im, geoms.size(), spec.table_mu),
                  "</mujoco>\n");
  return x;
}

}  // namespace

absl::StatusOr<TickPlans> PlanTickRange(const GraspConfig& config, const GraspSetup::Impl& im,
                                        const std::vector<planner::Contact>& contacts, int first) {
  planner::PlanProblem base = im.plan_base;
  base.contacts = contacts;
  planner::Inertia unused;
  ApplyPlanningModel(config.planning_model, &base, &unused);
  const planner::TrajectoryProblem traj =
      TickTrajectory(im, 1.0 / config.control_rate, base, first);
  auto planned =
      planner::PlanTrajectory(traj, im.plan_options, planner::SolverKind::kGeometric, true);
  if (!planned.ok())
    return io::PrependPath(absl::InternalError(planned.status().message()), "planner");
  TickPlans out;
  for (size_t k = 0; k < traj.steps.size(); ++k) {
    const planner::PlanResult& r = planned->steps[k];
    if (r.status != planner::PlanStatus::kOptimal)
      return absl::FailedPreconditionError(absl::StrFormat(
          "planner: step %d is %s", first + static_cast<int>(k), planner::ToString(r.status)));
    std::vector<double> fd;
    std::vector<Vec3> ff;
    for (int i = 0; i < im.n_fingers; ++i)
      fd.push_back(r.normal_forces[i]), ff.push_back(r.forces[i]);
    out.desired.push_back(std::move(fd));
    out.force.push_back(std::move(ff));
    out.problem.push_back(planner::StepProblem(traj, static_cast<int>(k)));
  }
  return out;
}

GraspSetup::~GraspSetup() = default;
const std::vector<std::string>& GraspSetup::finger_names() const { return impl_->finger_names; }

absl::StatusOr<std::unique_ptr<GraspSetup>> GraspSetup::Create(const GraspConfig& config) {
  TF_RETURN_IF_ERROR(ValidateGraspConfig(config));
  const ObjectSpec* spec = FindObjectSpec(config.object);
  if (spec == nullptr)
    return absl::InternalError(
        absl::StrCat("object: no specification for '", ToString(config.object), "'"));
  std::unique_ptr<GraspSetup> setup(new GraspSetup());
  setup->config_ = config;
  setup->impl_ = std::make_unique<Impl>();
  TF_ASSIGN_OR_RETURN(planner::PlanOptions options,
                      SetUpObjectAndMotion(config, *spec, setup->impl_.get()));
  setup->impl_->plan_options = options;
  setup->impl_->fingertip = {config.fingertip_radius, sim::FingertipGeometry{}.body_length};
  double deg = config.normal_uncertainty_deg;
  if (deg < 0 && config.sensor_array == SensorArray::kTaxel)
    deg = sim::DomeResolutionDeg(sim::DefaultFingertip(setup->impl_->fingertip),
                                 setup->impl_->fingertip);
  setup->impl_->sin_normal_uncertainty = deg > 0 ? std::sin(deg * std::numbers::pi / 180) : 0.0;
  if (config.fault.kind != SensorFault::Kind::kNone &&
      config.fault.finger >= setup->impl_->n_fingers)
    return absl::InvalidArgumentError(
        absl::StrFormat("fault.finger: must be < %d (the %s grasp's fingers), got %d",
                        setup->impl_->n_fingers, ToString(config.object), config.fault.finger));
  TF_RETURN_IF_ERROR(PlanTicks(config, options, setup->impl_.get()));
  setup->mjcf_ = GraspMjcf(config, *spec, *setup->impl_);
  // Compile once here so model errors surface at set-up.
  TF_RETURN_IF_ERROR(Scene::FromMjcf(setup->mjcf_).status());
  return setup;
}

}  // namespace tactforce::experiment
