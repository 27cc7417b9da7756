// Proto <-> planner conversions (convert.h). Unset request fields keep the
// planner's own defaults (a default-constructed PlanOptions / ObjectModel);
// only enum numbers the API does not define are rejected here.
#include "tactforce/api/convert.h"

#include <algorithm>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include "absl/functional/function_ref.h"
#include "absl/status/status.h"
#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "tactforce/planner/parameter_uncertainty.h"
#include "tactforce/planner/validation.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::api {
namespace {

absl::Status UnknownValue(absl::string_view field, int value) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": unknown value ", value));
}

absl::StatusOr<planner::ContactKind> ContactKindFromProto(v1::ContactKind kind,
                                                          absl::string_view field) {
  switch (kind) {
    case v1::CONTACT_KIND_UNSPECIFIED:
    case v1::CONTACT_KIND_INTRINSIC:
      return planner::ContactKind::kIntrinsic;
    case v1::CONTACT_KIND_EXTRINSIC:
      return planner::ContactKind::kExtrinsic;
    default:
      return UnknownValue(field, static_cast<int>(kind));
  }
}

absl::StatusOr<planner::ConeModel> ConeFromProto(v1::ConeModel cone) {
  switch (cone) {
    case v1::CONE_MODEL_UNSPECIFIED:
    case v1::CONE_MODEL_PYRAMID:
      return planner::ConeModel::kPyramid;
    case v1::CONE_MODEL_EXACT:
      return planner::ConeModel::kExact;
    default:
      return UnknownValue("cone", static_cast<int>(cone));
  }
}

absl::StatusOr<planner::SolverKind> SolverFromProto(v1::Solver solver) {
  switch (solver) {
    case v1::SOLVER_UNSPECIFIED:
    case v1::SOLVER_GEOMETRIC:
      return planner::SolverKind::kGeometric;
    case v1::SOLVER_IPOPT:
      return planner::SolverKind::kIpopt;
    case v1::SOLVER_CROSS_CHECK:
      return planner::SolverKind::kCrossCheck;
    default:
      return UnknownValue("solver", static_cast<int>(solver));
  }
}

v1::UncertaintySource ToProto(planner::UncertaintySource source) {
  switch (source) {
    case planner::UncertaintySource::kNone:
      return v1::UNCERTAINTY_SOURCE_UNSPECIFIED;
    case planner::UncertaintySource::kNominal:
      return v1::UNCERTAINTY_SOURCE_NOMINAL;
    case planner::UncertaintySource::kMeasurement:
      return v1::UNCERTAINTY_SOURCE_MEASUREMENT;
    case planner::UncertaintySource::kParameters:
      return v1::UNCERTAINTY_SOURCE_PARAMETERS;
    case planner::UncertaintySource::kFriction:
      return v1::UNCERTAINTY_SOURCE_FRICTION;
    case planner::UncertaintySource::kCombined:
      return v1::UNCERTAINTY_SOURCE_COMBINED;
  }
  return v1::UNCERTAINTY_SOURCE_UNSPECIFIED;
}

}  // namespace

absl::Status UncertaintyFromProto(const v1::ParameterUncertainty& in, double mass,
                                  const planner::Vec3& com, planner::ParameterUncertainty* out) {
  if (in.has_confidence()) out->confidence = in.confidence();
  const bool short_form = in.mass_sigma() != 0.0 || in.com_covariance_size() > 0;
  if (in.covariance_size() > 0 && short_form) {
    return absl::InvalidArgumentError(
        "object.uncertainty: give either covariance or mass_sigma / com_covariance, not both");
  }
  if (in.covariance_size() > 0) {
    if (in.covariance_size() != 100) {
      return absl::InvalidArgumentError(
          absl::StrCat("object.uncertainty.covariance: ", in.covariance_size(),
                       " entries, need 100 (10x10 row-major)"));
    }
    for (int k = 0; k < 100; ++k) out->covariance(k / 10, k % 10) = in.covariance(k);
    return absl::OkStatus();  // checked by the planner's validation
  }
  if (!short_form) return absl::OkStatus();
  if (!std::isfinite(in.mass_sigma()) || in.mass_sigma() < 0.0 ||
      in.mass_sigma() > planner::kMaxMass) {
    return absl::InvalidArgumentError(absl::StrCat("object.uncertainty.mass_sigma: must be in [0, ",
                                                   planner::kMaxMass, "] kg, got ",
                                                   in.mass_sigma()));
  }
  Eigen::Matrix3d com_covariance = Eigen::Matrix3d::Zero();
  if (in.com_covariance_size() > 0) {
    if (in.com_covariance_size() != 9) {
      return absl::InvalidArgumentError(
          absl::StrCat("object.uncertainty.com_covariance: ", in.com_covariance_size(),
                       " entries, need 9 (3x3 row-major)"));
    }
    for (int k = 0; k < 9; ++k) com_covariance(k / 3, k % 3) = in.com_covariance(k);
    TF_RETURN_IF_ERROR(planner::CheckCovariance("object.uncertainty.com_covariance", com_covariance,
                                                planner::kMaxLength * planner::kMaxLength));
  }
  out->covariance = planner::CovarianceFromMassAndCom(mass, com, in.mass_sigma(), com_covariance);
  return absl::OkStatus();
}

planner::Vec3 FromProto(const v1::Vec3& v) { return planner::Vec3(v.x(), v.y(), v.z()); }

v1::Vec3 ToProto(const planner::Vec3& v) {
  v1::Vec3 out;
  out.set_x(v.x());
  out.set_y(v.y());
  out.set_z(v.z());
  return out;
}

namespace {

// Every field of `c` from `in` (a reused contact keeps only its name's
// storage). Errors name the field under the contact's `path`
// ("contacts[2].kind: unknown value 7"), which is built only then: this
// runs for every contact of every Plan.
absl::Status ContactInto(const v1::Contact& in, absl::FunctionRef<std::string()> path,
                         planner::Contact* c) {
  c->name = in.name();
  c->position = FromProto(in.position());
  c->normal = FromProto(in.normal());
  c->friction = in.friction();
  c->friction_sigma = in.friction_sigma();
  if (absl::StatusOr<planner::ContactKind> kind = ContactKindFromProto(in.kind(), "kind");
      kind.ok()) {
    c->kind = *kind;
  } else {
    return ContactKindFromProto(in.kind(), path() + ".kind").status();
  }
  c->sigma = in.sigma();
  c->min_normal_force = in.min_normal_force();
  c->max_normal_force = in.max_normal_force();
  return absl::OkStatus();
}

// `request`'s problem into `problem`, whose contact list (and the names'
// strings) is reused: a warm thread converts without allocating.
absl::Status ProblemInto(const v1::PlanRequest& request, planner::PlanProblem* problem) {
  const v1::ObjectModel& object = request.object();
  problem->object = planner::ObjectModel();  // absent gravity: the planner's (0, 0, -9.81)
  problem->object.mass = object.mass();
  problem->object.com = FromProto(object.com());
  if (object.has_gravity()) problem->object.gravity = FromProto(object.gravity());
  // A single plan does not use the inertia, but a given one must be physical.
  if (object.has_inertia()) {
    const v1::Inertia& in = object.inertia();
    TF_RETURN_IF_ERROR(
        planner::ValidateInertia({in.ixx(), in.iyy(), in.izz(), in.ixy(), in.ixz(), in.iyz()}));
  }
  if (object.has_uncertainty()) {
    TF_RETURN_IF_ERROR(UncertaintyFromProto(object.uncertainty(), problem->object.mass,
                                            problem->object.com, &problem->object.uncertainty));
  }
  problem->contacts.resize(static_cast<size_t>(request.contacts_size()));
  for (int i = 0; i < request.contacts_size(); ++i) {
    TF_RETURN_IF_ERROR(ContactInto(
        request.contacts(i), [i] { return absl::StrCat("contacts[", i, "]"); },
        &problem->contacts[i]));
  }
  problem->external_wrench.force = FromProto(request.external_wrench().force());
  problem->external_wrench.torque = FromProto(request.external_wrench().torque());
  problem->motion = planner::Motion();
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<planner::Contact> ContactFromProto(const v1::Contact& in, const std::string& path) {
  planner::Contact c;
  TF_RETURN_IF_ERROR(ContactInto(
      in, [&path] { return path; }, &c));
  return c;
}

absl::StatusOr<planner::PlanProblem> ToProblem(const v1::PlanRequest& request) {
  planner::PlanProblem problem;
  TF_RETURN_IF_ERROR(ProblemInto(request, &problem));
  return problem;
}

absl::StatusOr<planner::PlanOptions> ToOptions(const v1::PlanRequest& request) {
  planner::PlanOptions options;  // unset fields keep these defaults
  TF_ASSIGN_OR_RETURN(options.cone, ConeFromProto(request.cone()));
  if (request.cone_sides() > static_cast<uint32_t>(std::numeric_limits<int>::max())) {
    // Would wrap to a negative int; the planner's range check sees the rest.
    return absl::InvalidArgumentError(
        absl::StrCat("cone_sides: must be in ", planner::PlanOptions::kMinConeSides, "..",
                     planner::PlanOptions::kMaxConeSides, ", got ", request.cone_sides()));
  }
  if (request.cone_sides() != 0) options.cone_sides = static_cast<int>(request.cone_sides());
  if (request.has_confidence()) options.confidence = request.confidence();
  TF_RETURN_IF_ERROR(ApplySolverOptions(request.solver_options(), &options));
  return options;
}

absl::Status ApplySolverOptions(const v1::SolverOptions& in, planner::PlanOptions* options) {
  if (in.has_ipopt_tolerance()) options->ipopt.tolerance = in.ipopt_tolerance();
  if (in.has_ipopt_max_iterations()) {
    // uint32 beyond int's range would wrap negative.
    options->ipopt.max_iterations = static_cast<int>(
        std::min<uint32_t>(in.ipopt_max_iterations(), std::numeric_limits<int>::max()));
  }
  if (in.has_ipopt_max_cpu_seconds()) options->ipopt.max_cpu_seconds = in.ipopt_max_cpu_seconds();
  if (in.has_rank_tolerance()) options->rank_tolerance = in.rank_tolerance();
  if (in.has_agreement_tolerance()) options->agreement_tolerance = in.agreement_tolerance();
  // Only the solver fields are named here; the request's other settings
  // (cone_sides, confidence) are checked where the planner validates them.
  std::string error;
  if (!options->IsValid(&error)) {
    for (const char* field : {"ipopt_", "rank_tolerance", "agreement_tolerance"}) {
      if (absl::StartsWith(error, field))
        return absl::InvalidArgumentError(absl::StrCat("solver_options.", error));
    }
  }
  return absl::OkStatus();
}

absl::StatusOr<planner::SolverKind> ToSolverKind(const v1::PlanRequest& request) {
  return SolverFromProto(request.solver());
}

absl::Status FromProto(const v1::PlanRequest& request, PlanCall* call) {
  // Field order of the message, so the first bad field is reported.
  TF_RETURN_IF_ERROR(ProblemInto(request, &call->problem));
  TF_ASSIGN_OR_RETURN(call->options, ToOptions(request));
  TF_ASSIGN_OR_RETURN(call->solver, ToSolverKind(request));
  return absl::OkStatus();
}

absl::StatusOr<PlanCall> FromProto(const v1::PlanRequest& request) {
  PlanCall call;
  TF_RETURN_IF_ERROR(FromProto(request, &call));
  return call;
}

v1::PlanStatus ToProto(planner::PlanStatus status) {
  switch (status) {
    case planner::PlanStatus::kOptimal:
      return v1::PLAN_STATUS_OPTIMAL;
    case planner::PlanStatus::kInfeasible:
      return v1::PLAN_STATUS_INFEASIBLE;
    case planner::PlanStatus::kSolverFailure:
      return v1::PLAN_STATUS_SOLVER_FAILURE;
  }
  return v1::PLAN_STATUS_UNSPECIFIED;
}

v1::Solver ToProto(planner::SolverKind solver) {
  switch (solver) {
    case planner::SolverKind::kGeometric:
      return v1::SOLVER_GEOMETRIC;
    case planner::SolverKind::kIpopt:
      return v1::SOLVER_IPOPT;
    case planner::SolverKind::kCrossCheck:
      return v1::SOLVER_CROSS_CHECK;
  }
  return v1::SOLVER_UNSPECIFIED;
}

v1::ContactKind ToProto(planner::ContactKind kind) {
  switch (kind) {
    case planner::ContactKind::kIntrinsic:
      return v1::CONTACT_KIND_INTRINSIC;
    case planner::ContactKind::kExtrinsic:
      return v1::CONTACT_KIND_EXTRINSIC;
  }
  return v1::CONTACT_KIND_UNSPECIFIED;
}

v1::ConeModel ToProto(planner::ConeModel cone) {
  switch (cone) {
    case planner::ConeModel::kPyramid:
      return v1::CONE_MODEL_PYRAMID;
    case planner::ConeModel::kExact:
      return v1::CONE_MODEL_EXACT;
  }
  return v1::CONE_MODEL_UNSPECIFIED;
}

v1::PlanRequest ToRequest(const planner::PlanProblem& problem, const planner::PlanOptions& options,
                          planner::SolverKind solver) {
  v1::PlanRequest request;
  v1::ObjectModel* object = request.mutable_object();
  object->set_mass(problem.object.mass);
  *object->mutable_com() = ToProto(problem.object.com);
  *object->mutable_gravity() = ToProto(problem.object.gravity);
  for (const planner::Contact& c : problem.contacts) {
    v1::Contact* out = request.add_contacts();
    out->set_name(c.name);
    *out->mutable_position() = ToProto(c.position);
    *out->mutable_normal() = ToProto(c.normal);
    out->set_friction(c.friction);
    out->set_kind(ToProto(c.kind));
    out->set_sigma(c.sigma);
    out->set_min_normal_force(c.min_normal_force);
    out->set_max_normal_force(c.max_normal_force);
    out->set_friction_sigma(c.friction_sigma);
  }
  const planner::ParameterUncertainty& u = problem.object.uncertainty;
  if (!u.covariance.isZero(0.0) || u.confidence.has_value()) {
    v1::ParameterUncertainty* pu = object->mutable_uncertainty();
    if (u.confidence.has_value()) pu->set_confidence(*u.confidence);
    if (!u.covariance.isZero(0.0)) {
      for (int k = 0; k < 100; ++k) pu->add_covariance(u.covariance(k / 10, k % 10));
    }
  }
  *request.mutable_external_wrench()->mutable_force() = ToProto(problem.external_wrench.force);
  *request.mutable_external_wrench()->mutable_torque() = ToProto(problem.external_wrench.torque);
  request.set_cone(ToProto(options.cone));
  // A negative count cannot be sent; 0 asks for the default, which the
  // planner's range check would not have accepted either way.
  request.set_cone_sides(options.cone_sides > 0 ? static_cast<uint32_t>(options.cone_sides) : 0u);
  request.set_confidence(options.confidence);
  request.set_solver(ToProto(solver));
  const planner::PlanOptions defaults;
  v1::SolverOptions* solver_options = request.mutable_solver_options();
  if (options.ipopt.tolerance != defaults.ipopt.tolerance)
    solver_options->set_ipopt_tolerance(options.ipopt.tolerance);
  if (options.ipopt.max_iterations != defaults.ipopt.max_iterations &&
      options.ipopt.max_iterations > 0) {
    solver_options->set_ipopt_max_iterations(static_cast<uint32_t>(options.ipopt.max_iterations));
  }
  if (options.ipopt.max_cpu_seconds != defaults.ipopt.max_cpu_seconds) {
    solver_options->set_ipopt_max_cpu_seconds(options.ipopt.max_cpu_seconds);
  }
  if (options.rank_tolerance != defaults.rank_tolerance)
    solver_options->set_rank_tolerance(options.rank_tolerance);
  if (options.agreement_tolerance != defaults.agreement_tolerance) {
    solver_options->set_agreement_tolerance(options.agreement_tolerance);
  }
  if (solver_options->ByteSizeLong() == 0) request.clear_solver_options();
  return request;
}

v1::PlanResponse ToProto(const planner::PlanResult& result) {
  v1::PlanResponse response;
  ToProto(result, &response);
  return response;
}

void ToProto(const planner::PlanResult& result, v1::PlanResponse* out) {
  v1::PlanResponse& response = *out;
  response.Clear();
  response.set_status(ToProto(result.status));
  response.set_message(result.message);
  for (const planner::Vec3& f : result.forces) *response.add_forces() = ToProto(f);
  for (double fn : result.normal_forces) response.add_normal_forces(fn);
  for (double s : result.normal_force_sigma) response.add_normal_force_sigma(s);
  response.set_objective(result.objective);
  response.set_min_margin(result.min_margin);
  response.set_solver(ToProto(result.solver));
  response.set_solve_time_us(result.solve_time_us);
  response.set_iterations(result.iterations);
  if (result.cross_check.has_value()) {
    const planner::CrossCheckReport& in = *result.cross_check;
    v1::CrossCheck* out = response.mutable_cross_check();
    out->set_agree(in.agree);
    out->set_max_force_diff(in.max_force_diff);
    out->set_objective_rel_diff(in.objective_rel_diff);
    out->set_geometric_time_us(in.geometric_time_us);
    out->set_ipopt_time_us(in.ipopt_time_us);
    out->set_ipopt_status(ToProto(in.ipopt_status));
    out->set_ipopt_message(in.ipopt_message);
  }
  for (const planner::RowMargin& m : result.row_margins) {
    v1::RowMargin* out = response.add_row_margins();
    out->set_contact(m.contact);
    out->set_constraint(m.cone         ? "exact friction cone"
                        : m.facet >= 0 ? absl::StrCat("friction cone facet ", m.facet)
                        : m.upper      ? "maximum normal force"
                                       : "minimum normal force");
    out->set_slack(m.slack);
    out->set_measurement(m.measurement);
    out->set_parameters(m.parameters);
  }
  response.set_infeasible_source(ToProto(result.infeasible_source));
}

absl::StatusOr<planner::TrajectoryProblem> ToTrajectoryProblem(const v1::TrajectoryRequest& request,
                                                               const planner::PlanProblem& base) {
  planner::TrajectoryProblem t;
  t.base = base;
  if (request.plan().object().has_inertia()) {
    const v1::Inertia& in = request.plan().object().inertia();
    t.inertia = planner::Inertia{in.ixx(), in.iyy(), in.izz(), in.ixy(), in.ixz(), in.iyz()};
  }
  for (int k = 0; k < request.steps_size(); ++k) {
    const v1::TrajectoryStep& in = request.steps(k);
    planner::TrajectoryStep step;
    step.gravity = in.has_gravity() ? FromProto(in.gravity()) : t.base.object.gravity;
    step.linear_acceleration = FromProto(in.linear_acceleration());
    step.angular_velocity = FromProto(in.angular_velocity());
    step.angular_acceleration = FromProto(in.angular_acceleration());
    step.external_wrench = {FromProto(in.external_wrench().force()),
                            FromProto(in.external_wrench().torque())};
    if (in.contacts_size() > 0) {
      std::vector<planner::Contact> contacts;
      for (int i = 0; i < in.contacts_size(); ++i) {
        TF_ASSIGN_OR_RETURN(
            planner::Contact c,
            ContactFromProto(in.contacts(i), absl::StrCat("steps[", k, "].contacts[", i, "]")));
        contacts.push_back(std::move(c));
      }
      step.contacts = std::move(contacts);
    }
    t.steps.push_back(std::move(step));
  }
  return t;
}

}  // namespace tactforce::api
