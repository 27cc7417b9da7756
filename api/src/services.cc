// The request handlers of services.h: each converts its request (field
// paths in errors), calls one library entry point and converts the answer.
#include "tactforce/api/services.h"

#include <cmath>
#include <cstdint>
#include <utility>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/finite.h"
#include "tactforce/audit/audit.h"
#include "tactforce/sim/sensor_model.h"
#include "tactforce/estimator/force_estimation.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/planner/validation.h"

namespace tactforce::api {
namespace {

// The limits of CallLimits that the libraries check themselves, set into
// the planner's options (the estimator's are its EstimateOptions::plan):
// the one place they cross from the call to the libraries.
void SetLibraryLimits(const CallLimits& limits, planner::PlanOptions* options) {
  options->max_contacts = limits.max_contacts;
}

// Prefixes field paths of a nested message ("plan" + "contacts[1].normal").
absl::Status Nested(const absl::Status& s, const char* field) {
  if (s.code() != absl::StatusCode::kInvalidArgument) return s;
  return io::PrependPath(s, field, ".");
}

v1::TrajectoryResponse ToProto(const planner::TrajectoryResult& r) {
  v1::TrajectoryResponse out;
  for (const planner::PlanResult& step : r.steps) *out.add_steps() = api::ToProto(step);
  out.set_optimal_steps(r.optimal);
  out.set_infeasible_steps(r.infeasible);
  out.set_failed_steps(r.failed);
  out.set_total_time_us(r.total_time_us);
  return out;
}

v1::EstimateStatus ToProto(estimator::EstimateStatus s) {
  switch (s) {
    case estimator::EstimateStatus::kOk:
      return v1::ESTIMATE_STATUS_OK;
    case estimator::EstimateStatus::kInfeasible:
      return v1::ESTIMATE_STATUS_INFEASIBLE;
    case estimator::EstimateStatus::kSolverFailure:
      return v1::ESTIMATE_STATUS_SOLVER_FAILURE;
  }
  return v1::ESTIMATE_STATUS_UNSPECIFIED;
}

// The planned steps of a motion or a probe, described for the limits'
// messages ("steps: 100 steps with 300 contacts in all ...").
struct PlannedSteps {
  const char* field;          // the request field that sets the count
  const char* steps_noun;     // "steps", "probe steps"
  const char* contacts_noun;  // "contacts", "holding contacts"
  double steps;               // in double: a nonsense count must not wrap
  double contacts;            // in all steps
  double extra_bytes;         // response bytes beside the steps' PlanResponses
};

// Work and response size of planned steps, bounded before any step is
// solved: an unauthenticated client must not buy minutes of CPU, and an
// answer too big to send must not be computed first.
absl::Status CheckPlannedSteps(const PlannedSteps& p, int cone_sides, const CallLimits& limits) {
  const double work = p.contacts * cone_sides;
  if (work > static_cast<double>(limits.max_trajectory_work)) {
    return absl::InvalidArgumentError(absl::StrCat(
        p.field, ": ", p.steps, " ", p.steps_noun, " with ", p.contacts, " ", p.contacts_noun,
        " in all at ", cone_sides, " cone sides exceed the limit of ", limits.max_trajectory_work,
        " (steps x contacts x cone sides; the server's --max-trajectory-work)"));
  }
  // A PlanResponse per step: status, solver, times (about 40 bytes) and per
  // contact a force (3 doubles), its normal force and sigma, with tags.
  constexpr double kStepBytes = 40, kContactBytes = 60;
  const double bytes = p.steps * kStepBytes + p.contacts * kContactBytes + p.extra_bytes;
  if (limits.max_response_bytes > 0 && bytes > static_cast<double>(limits.max_response_bytes)) {
    return absl::InvalidArgumentError(
        absl::StrCat(p.field, ": the response of ", p.steps, " ", p.steps_noun, " would be about ",
                     bytes, " bytes, over the limit of ", limits.max_response_bytes,
                     " (the server's --max-message-bytes)"));
  }
  return absl::OkStatus();
}

// An audit's answer does not grow with its samples: models, report (every
// candidate effect) and summary take at most kAuditAnswerBytes (about 12 kB
// with one cause; a cause adds its parameters) plus the strings the request
// echoes: the source (report, summary, both models' JSON), the units and a
// given model (extended and reported).
absl::Status CheckAuditResponseSize(const v1::AuditRequest& r, const CallLimits& limits) {
  constexpr double kAuditAnswerBytes = 64 * 1024;
  const double bytes = kAuditAnswerBytes +
                       4.0 * static_cast<double>(r.source().size() + r.reading_units().size()) +
                       2.0 * static_cast<double>(r.model_json().size());
  if (limits.max_response_bytes > 0 && bytes > static_cast<double>(limits.max_response_bytes)) {
    return absl::InvalidArgumentError(
        absl::StrCat("source, reading_units, model_json: the response (report, summary and models "
                     "echoing them) would be up to ",
                     bytes, " bytes, over the limit of ", limits.max_response_bytes,
                     " (the server's --max-message-bytes)"));
  }
  return absl::OkStatus();
}

absl::Status CheckTrajectorySize(const planner::TrajectoryProblem& t,
                                 const planner::PlanOptions& options, const CallLimits& limits) {
  double contacts = 0;
  for (const planner::TrajectoryStep& step : t.steps) {
    contacts += static_cast<double>(step.contacts ? step.contacts->size() : t.base.contacts.size());
  }
  return CheckPlannedSteps(
      {"steps", "steps", "contacts", static_cast<double>(t.steps.size()), contacts, 0.0},
      options.cone_sides, limits);
}

// The probe's numbers as the planner checks them, under the request's own
// field names ("normal: zero length"; the planner says "probe.normal").
absl::Status CheckProbe(const planner::FrictionProbe& probe) {
  planner::Vec3 unit_normal, unit_tangent;
  absl::Status s = planner::ValidateFrictionProbe(probe, &unit_normal, &unit_tangent);
  constexpr absl::string_view kPrefix = "probe.";
  if (s.ok() || !absl::StartsWith(s.message(), kPrefix)) return s;
  return absl::Status(s.code(), s.message().substr(kPrefix.size()));
}

// The holding grasp of a motion or probe, checked whole before any step
// ("plan.contacts[1].friction: not a finite number"): steps that replace
// the contacts would otherwise never look at it.
absl::Status CheckHoldingGrasp(const PlanCall& call) {
  return Nested(planner::ValidateProblem(call.problem, call.options).status(), "plan");
}

}  // namespace

absl::Status PreparePlan(const v1::PlanRequest& request, const CallLimits& limits, PlanCall* call) {
  TF_RETURN_IF_ERROR(FromProto(request, call));
  SetLibraryLimits(limits, &call->options);
  // The tighter of the request's and the server's CPU limits (0 = none).
  const double cap = limits.solve_timeout_seconds();
  double& asked = call->options.ipopt.max_cpu_seconds;
  if (cap > 0 && (asked == 0 || cap < asked)) asked = cap;
  return absl::OkStatus();
}

absl::StatusOr<PlanCall> PreparePlan(const v1::PlanRequest& request, const CallLimits& limits) {
  PlanCall call;
  TF_RETURN_IF_ERROR(PreparePlan(request, limits, &call));
  return call;
}

absl::StatusOr<ValidPlanCall> ValidatePlan(const PlanCall& call) {
  ValidPlanCall valid;
  TF_RETURN_IF_ERROR(planner::ValidatePlan(call.problem, call.options, &valid.plan));
  valid.solver = call.solver;
  return valid;
}

PlanBuffers& ThreadPlanBuffers() {
  thread_local PlanBuffers buffers;
  return buffers;
}

namespace {

// Into `response` (the caller's, e.g. on a gRPC call's arena: filled in
// place, no copy), then the finite check every answer gets.
absl::Status FillPlanResponse(const PlanBuffers& buffers, v1::PlanResponse* response) {
  api::ToProto(buffers.result, response);
  return CheckFiniteAnswer(*response);
}

template <class Call>
absl::StatusOr<v1::PlanResponse> SolvePlanToValue(const Call& call, const CallState& state,
                                                  PlanBuffers* buffers) {
  v1::PlanResponse response;
  TF_RETURN_IF_ERROR(SolvePlan(call, state, buffers, &response));
  return response;
}

}  // namespace

absl::Status SolvePlan(const PlanCall& call, const CallState& state, PlanBuffers* buffers,
                       v1::PlanResponse* response) {
  PlanBuffers& b = buffers != nullptr ? *buffers : ThreadPlanBuffers();
  TF_RETURN_IF_ERROR(planner::Plan(call.problem, call.options, call.solver, &b.workspace, &b.result,
                                   planner::SolveControl{state.interrupt}));
  return FillPlanResponse(b, response);
}

absl::Status SolvePlan(const ValidPlanCall& call, const CallState& state, PlanBuffers* buffers,
                       v1::PlanResponse* response) {
  PlanBuffers& b = buffers != nullptr ? *buffers : ThreadPlanBuffers();
  TF_RETURN_IF_ERROR(
      planner::CachedSolver(call.solver)
          .Solve(call.plan, &b.workspace, &b.result, planner::SolveControl{state.interrupt}));
  return FillPlanResponse(b, response);
}

absl::StatusOr<v1::PlanResponse> SolvePlan(const PlanCall& call, const CallState& state,
                                           PlanBuffers* buffers) {
  return SolvePlanToValue(call, state, buffers);
}

absl::StatusOr<v1::PlanResponse> SolvePlan(const ValidPlanCall& call, const CallState& state,
                                           PlanBuffers* buffers) {
  return SolvePlanToValue(call, state, buffers);
}

absl::StatusOr<v1::PlanResponse> HandlePlan(const v1::PlanRequest& request,
                                            const CallLimits& limits, const CallState& state) {
  TF_ASSIGN_OR_RETURN(const PlanCall call, PreparePlan(request, limits));
  return SolvePlan(call, state);
}

absl::StatusOr<v1::TrajectoryResponse> HandleTrajectory(const v1::TrajectoryRequest& request,
                                                        const CallLimits& limits,
                                                        const CallState& state) {
  absl::StatusOr<PlanCall> call = PreparePlan(request.plan(), limits);
  if (!call.ok()) return Nested(call.status(), "plan");
  TF_RETURN_IF_ERROR(CheckHoldingGrasp(*call));
  TF_ASSIGN_OR_RETURN(planner::TrajectoryProblem t, ToTrajectoryProblem(request, call->problem));
  TF_RETURN_IF_ERROR(CheckTrajectorySize(t, call->options, limits));
  const bool warm = !request.has_warm_start() || request.warm_start();
  TF_ASSIGN_OR_RETURN(planner::TrajectoryResult r,
                      planner::PlanTrajectory(t, call->options, call->solver, warm,
                                              planner::SolveControl{state.interrupt}));
  return FiniteAnswer<v1::TrajectoryResponse>(ToProto(r));
}

absl::StatusOr<v1::FrictionProbeResponse> HandleFrictionProbe(
    const v1::FrictionProbeRequest& request, const CallLimits& limits, const CallState& state) {
  absl::StatusOr<PlanCall> call = PreparePlan(request.plan(), limits);
  if (!call.ok()) return Nested(call.status(), "plan");
  TF_RETURN_IF_ERROR(CheckHoldingGrasp(*call));
  planner::FrictionProbe probe;
  probe.position = FromProto(request.position());
  probe.normal = FromProto(request.normal());
  probe.tangent = FromProto(request.tangent());
  probe.tangential_force = request.tangential_force();
  probe.initial_normal_force = request.initial_normal_force();
  probe.final_normal_force = request.final_normal_force();
  probe.ramp_rate = request.ramp_rate();
  probe.sample_rate = request.sample_rate();
  TF_RETURN_IF_ERROR(CheckProbe(probe));
  // The same work and size bounds as a trajectory, on the step count the
  // ramp implies (in double: it may be beyond any integer).
  const double steps = std::floor((probe.initial_normal_force - probe.final_normal_force) /
                                  probe.ramp_rate * probe.sample_rate) +
                       1;
  // Per step a time (8 bytes) and a probe force (3 doubles), with tags.
  constexpr double kProbeStepBytes = 40;
  TF_RETURN_IF_ERROR(CheckPlannedSteps(
      {"sample_rate", "probe steps", "holding contacts", steps,
       steps * static_cast<double>(call->problem.contacts.size()), steps * kProbeStepBytes},
      call->options.cone_sides, limits));
  TF_ASSIGN_OR_RETURN(planner::ProbePlan plan,
                      planner::PlanFrictionProbe(call->problem, probe, call->options, call->solver,
                                                 planner::SolveControl{state.interrupt}));
  v1::FrictionProbeResponse out;
  for (double t : plan.times) out.add_times(t);
  for (const auto& f : plan.probe_forces) *out.add_probe_forces() = api::ToProto(f);
  *out.mutable_holding() = ToProto(plan.holding);
  return FiniteAnswer<v1::FrictionProbeResponse>(std::move(out));
}

absl::StatusOr<v1::EstimateResponse> HandleEstimate(const v1::EstimateRequest& request,
                                                    const CallLimits& limits,
                                                    const CallState& /*state*/) {
  v1::PlanRequest as_plan;
  *as_plan.mutable_object() = request.object();
  *as_plan.mutable_contacts() = request.contacts();
  *as_plan.mutable_external_wrench() = request.external_wrench();
  TF_ASSIGN_OR_RETURN(planner::PlanProblem problem, ToProblem(as_plan));
  estimator::EstimateOptions o;
  switch (request.method()) {
    case v1::ESTIMATE_METHOD_UNSPECIFIED:
    case v1::ESTIMATE_METHOD_PROJECTION:
      o.method = estimator::EstimateMethod::kProjection;
      break;
    case v1::ESTIMATE_METHOD_NORMAL_LSQ:
      o.method = estimator::EstimateMethod::kNormalLsq;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("method: unknown value ", static_cast<int>(request.method())));
  }
  if (request.has_origin_weight()) o.origin_weight = request.origin_weight();
  if (request.cone_sides() > planner::PlanOptions::kMaxConeSides)
    return absl::InvalidArgumentError(absl::StrCat("cone_sides: must be in ",
                                                   planner::PlanOptions::kMinConeSides, "..",
                                                   planner::PlanOptions::kMaxConeSides));
  if (request.cone_sides() != 0) o.plan.cone_sides = static_cast<int>(request.cone_sides());
  SetLibraryLimits(limits, &o.plan);
  const std::vector<double> readings(request.readings().begin(), request.readings().end());
  // The worker thread's buffers: warm estimates allocate only the response.
  thread_local estimator::EstimationWorkspace workspace;
  thread_local estimator::ForceEstimate estimate;
  TF_RETURN_IF_ERROR(estimator::EstimateForces(problem, readings, o, &workspace, &estimate));
  const estimator::ForceEstimate* e = &estimate;
  v1::EstimateResponse out;
  out.set_status(ToProto(e->status));
  out.set_message(e->message);
  for (const auto& f : e->forces) *out.add_forces() = api::ToProto(f);
  for (double v : e->normal_forces) out.add_normal_forces(v);
  for (double v : e->residuals) out.add_residuals(v);
  out.set_method(e->method == estimator::EstimateMethod::kProjection
                     ? v1::ESTIMATE_METHOD_PROJECTION
                     : v1::ESTIMATE_METHOD_NORMAL_LSQ);
  for (int j : e->negative_readings) out.add_negative_readings(j);
  out.set_solve_time_us(e->solve_time_us);
  out.set_iterations(e->iterations);
  return FiniteAnswer<v1::EstimateResponse>(std::move(out));
}

absl::StatusOr<v1::FrictionResponse> HandleFriction(const v1::FrictionRequest& request,
                                                    const CallLimits& /*limits*/,
                                                    const CallState& state) {
  std::vector<estimator::FrictionTrial> trials;
  for (int i = 0; i < request.trials_size(); ++i) {
    const v1::FrictionTrial& in = request.trials(i);
    estimator::FrictionTrial trial;
    trial.name = in.name().empty() ? absl::StrCat("trial", i) : in.name();
    if (in.has_normal()) trial.normal = FromProto(in.normal());
    for (const v1::FrictionSample& s : in.samples()) {
      estimator::FrictionSample out;
      out.t = s.t();
      out.force = FromProto(s.force());
      out.contact_point = FromProto(s.contact_point());
      if (s.has_slip()) out.slip = s.slip();
      trial.samples.push_back(out);
    }
    trials.push_back(std::move(trial));
  }
  estimator::FrictionOptions o;
  o.interrupt = state.interrupt;
  if (request.mesh().triangles_size() > 0 || request.mesh().vertices_size() > 0) {
    io::TriangleMesh mesh;
    for (int i = 0; i < request.mesh().vertices_size(); ++i) {
      const planner::Vec3 v = FromProto(request.mesh().vertices(i));
      if (!planner::IsBounded(v, planner::kMaxLength))
        return planner::MagnitudeError(absl::StrCat("mesh.vertices[", i, "]"), v,
                                       planner::kMaxLength, "m");
      mesh.vertices.push_back(v);
    }
    for (const auto& t : request.mesh().triangles())
      mesh.triangles.push_back({t.a(), t.b(), t.c()});
    o.mesh = std::move(mesh);
  }
  if (request.has_slip_distance()) o.slip_distance = request.slip_distance();
  if (request.has_window())
    o.window = static_cast<int>(std::min<uint32_t>(request.window(), 1u << 20));
  if (request.has_fit_window())
    o.fit_window = static_cast<int>(std::min<uint32_t>(request.fit_window(), 1u << 20));
  if (request.has_min_normal_force()) o.min_normal_force = request.min_normal_force();
  switch (request.pre_slip()) {
    case v1::PRE_SLIP_FORCE_UNSPECIFIED:
    case v1::PRE_SLIP_FORCE_WINDOW_AVERAGE:
      o.pre_slip = estimator::PreSlipForce::kWindowAverage;
      break;
    case v1::PRE_SLIP_FORCE_LINEAR_FIT:
      o.pre_slip = estimator::PreSlipForce::kLinearFit;
      break;
    default:
      return absl::InvalidArgumentError(
          absl::StrCat("pre_slip: unknown value ", static_cast<int>(request.pre_slip())));
  }
  TF_ASSIGN_OR_RETURN(estimator::FrictionEstimate e, estimator::EstimateFriction(trials, o));
  v1::FrictionResponse out;
  for (const auto& t : e.trials) {
    v1::TrialFriction* r = out.add_trials();
    r->set_name(t.name);
    r->set_slipped(t.slipped);
    r->set_valid(t.valid);
    r->set_mu(t.mu);
    r->set_mu_sigma(t.mu_sigma);
    r->set_lower_bound(t.lower_bound);
    r->set_slip_time(t.slip_time);
    r->set_slip_index(t.slip_index);
    r->set_force_angle(t.force_angle);
    *r->mutable_normal() = api::ToProto(t.normal);
    r->set_mesh_triangle(t.mesh_triangle);
    r->set_message(t.message);
  }
  out.set_median(e.median);
  out.set_mean(e.mean);
  out.set_iqr(e.iqr);
  out.set_mu_sigma(e.mu_sigma);
  out.set_count(e.count);
  return FiniteAnswer<v1::FrictionResponse>(std::move(out));
}

namespace {

// The samples' per-taxel readings into data->taxels (taxel-major); every
// sample must carry the same count (InvalidArgument naming the sample).
absl::Status ReadAuditTaxels(const v1::AuditRequest& request, audit::MeasuredData* data) {
  if (request.samples_size() == 0 || request.samples(0).taxels_size() == 0) {
    for (int k = 0; k < request.samples_size(); ++k)
      if (request.samples(k).taxels_size() != 0)
        return absl::InvalidArgumentError(
            absl::StrCat("samples[", k, "].taxels: ", request.samples(k).taxels_size(),
                         " values, samples[0] has none"));
    return absl::OkStatus();
  }
  const int m = request.samples(0).taxels_size();
  if (m > audit::kMaxTaxels)
    return absl::InvalidArgumentError(
        absl::StrCat("samples[0].taxels: ", m, " values exceed ", audit::kMaxTaxels));
  data->taxels.assign(m, std::vector<double>(request.samples_size()));
  for (int k = 0; k < request.samples_size(); ++k) {
    const v1::AuditSample& s = request.samples(k);
    if (s.taxels_size() != m)
      return absl::InvalidArgumentError(absl::StrCat("samples[", k, "].taxels: ", s.taxels_size(),
                                                     " values, samples[0] has ", m));
    for (int j = 0; j < m; ++j) data->taxels[j][k] = s.taxels(j);
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<v1::AuditResponse> HandleAudit(const v1::AuditRequest& request,
                                              const CallLimits& limits, const CallState& state) {
  if (request.samples_size() > limits.max_audit_samples) {
    return absl::InvalidArgumentError(
        absl::StrCat("samples: ", request.samples_size(), " samples exceed the limit of ",
                     limits.max_audit_samples, " per request (the server's --max-audit-samples)"));
  }
  TF_RETURN_IF_ERROR(CheckAuditResponseSize(request, limits));
  audit::MeasuredData data;
  data.source = request.source().empty() ? "request" : request.source();
  bool any_shear = false;
  for (const auto& s : request.samples()) any_shear |= s.has_shear();
  int segment_trial = 0;
  for (int k = 0; k < request.samples_size(); ++k) {
    const v1::AuditSample& s = request.samples(k);
    if (any_shear && !s.has_shear())
      return absl::InvalidArgumentError(
          absl::StrCat("samples[", k, "].shear: missing (other samples have it)"));
    data.t.push_back(s.t());
    data.reference.push_back(s.reference());
    data.reading.push_back(s.reading());
    if (any_shear) data.shear.push_back(s.shear());
    data.trial.push_back(s.trial());
    if (k == 0 || s.trial() != segment_trial) data.segment_starts.push_back(k);
    segment_trial = s.trial();
  }
  TF_RETURN_IF_ERROR(ReadAuditTaxels(request, &data));
  TF_RETURN_IF_ERROR(audit::ValidateMeasuredData(data));
  audit::AuditOptions options;
  options.interrupt = state.interrupt;
  if (request.has_heldout_fraction()) options.heldout_fraction = request.heldout_fraction();
  if (request.has_max_causes()) options.max_causes = request.max_causes();
  if (request.has_blocks()) options.blocks = request.blocks();
  if (!request.reading_units().empty()) options.reading_units = request.reading_units();
  if (!request.model_json().empty()) {
    TF_ASSIGN_OR_RETURN(options.model,
                        sim::SensorModelFromJson(request.model_json(), "model_json"));
  }
  TF_ASSIGN_OR_RETURN(audit::AuditReport report, audit::RunAudit(data, options));
  v1::AuditResponse out;
  out.set_nominal_adequate(report.nominal_adequate);
  for (const audit::Cause& c : report.causes) {
    v1::AuditCause* cause = out.add_causes();
    cause->set_effect(c.effect);
    cause->set_form(c.form);
    for (const auto& [k, values] : c.array_parameters) {
      v1::DoubleList& list = (*cause->mutable_array_parameters())[k];
      for (double v : values) list.add_values(v);
    }
    for (const auto& [k, v] : c.parameters) (*cause->mutable_parameters())[k] = v;
    for (const auto& [k, v] : c.uncertainties) (*cause->mutable_uncertainties())[k] = v;
    cause->set_heldout_rms_before(c.heldout_rms_before);
    cause->set_heldout_rms_after(c.heldout_rms_after);
    cause->set_gain(c.gain);
    cause->set_found_by(c.found_by);
    for (int b : c.blocks) cause->add_blocks(b);
  }
  out.set_heldout_rms_before(report.heldout_rms_before);
  out.set_heldout_rms_after(report.heldout_rms_after);
  out.set_gain(report.gain);
  out.set_extended_model_json(sim::SensorModelToJson(report.extended_model));
  out.set_report_json(audit::AuditReportJson(report));
  out.set_summary(audit::FormatAuditSummary(report));
  return FiniteAnswer<v1::AuditResponse>(std::move(out));
}

}  // namespace tactforce::api
