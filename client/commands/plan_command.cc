// `tactforce plan`: one PlanRequest, TrajectoryRequest (--trajectory) or
// FrictionProbeRequest (--friction-probe) through the Backend (backend.h:
// in this process, or tactforce-server with --server); JSON or a table out.
#include "plan_command.h"

#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <memory>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "backend.h"
#include "tactforce/api/estimates.h"
#include "tactforce/api/json.h"
#include "tactforce/api/names.h"
#include "tactforce/api/plan_plot.h"
#include "tactforce/api/services.h"
#include "tactforce/api/table.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/io/text_file.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::cli {
namespace {

// --solver and the solver options; each overrides the request's field.
void AddSolverFlags(CLI::App* cmd, PlanArgs* args) {
  cmd->add_option("--solver", args->solver,
                  "Override the request's solver: geometric, ipopt or cross-check")
      ->check(CLI::IsMember({"geometric", "ipopt", "cross-check"}));
  cmd->add_option("--ipopt-tol", args->ipopt_tolerance,
                  "Ipopt's convergence tolerance (> 0; default 1e-9)")
      ->check(GreaterThan(0));
  cmd->add_option("--max-iterations", args->max_iterations,
                  "Ipopt iteration limit (>= 1; default 3000)")
      ->check(Between(1, 1e6));
  cmd->add_option("--ipopt-max-seconds", args->ipopt_max_seconds,
                  "Ipopt CPU-time limit (s, >= 0; 0 = none)")
      ->check(AtLeast(0));
  cmd->add_option("--rank-tol", args->rank_tolerance,
                  "Relative singular-value cut-off of the grasp matrix's null space (0 < x < 1e-2; "
                  "default 1e-9)")
      ->check(GreaterThan(0));
  cmd->add_option(
         "--agreement-tol", args->agreement_tolerance,
         "cross-check: largest force difference (N) counted as agreement (> 0; default 1e-5)")
      ->check(GreaterThan(0));
}

void ApplySolverFlags(const PlanArgs& args, v1::PlanRequest* request) {
  if (args.solver == "geometric") request->set_solver(v1::SOLVER_GEOMETRIC);
  if (args.solver == "ipopt") request->set_solver(v1::SOLVER_IPOPT);
  if (args.solver == "cross-check") request->set_solver(v1::SOLVER_CROSS_CHECK);
  v1::SolverOptions* o = request->mutable_solver_options();
  if (args.ipopt_tolerance) o->set_ipopt_tolerance(*args.ipopt_tolerance);
  if (args.max_iterations) o->set_ipopt_max_iterations(static_cast<uint32_t>(*args.max_iterations));
  if (args.ipopt_max_seconds) o->set_ipopt_max_cpu_seconds(*args.ipopt_max_seconds);
  if (args.rank_tolerance) o->set_rank_tolerance(*args.rank_tolerance);
  if (args.agreement_tolerance) o->set_agreement_tolerance(*args.agreement_tolerance);
}

// --inertia / --friction: earlier estimates, with their uncertainty, into
// the request (api/estimates.h). Errors name the flag.
absl::Status ApplyEstimateFlags(const PlanArgs& args, v1::PlanRequest* request) {
  if (!args.inertia_path.empty()) {
    absl::StatusOr<std::string> text = ReadInput(args.inertia_path);
    if (!text.ok()) return io::PrependPath(text.status(), "--inertia");
    v1::FitInertiaResponse fit;
    if (absl::Status s = api::ParseJson(*text, &fit, InputName(args.inertia_path)); !s.ok()) {
      return io::PrependPath(s, "--inertia");
    }
    TF_RETURN_IF_ERROR(api::ApplyInertiaFit(fit, "--inertia", request));
  }
  if (!args.friction_path.empty()) {
    absl::StatusOr<std::string> text = ReadInput(args.friction_path);
    if (!text.ok()) return io::PrependPath(text.status(), "--friction");
    v1::FrictionResponse friction;
    if (absl::Status s = api::ParseJson(*text, &friction, InputName(args.friction_path)); !s.ok()) {
      return io::PrependPath(s, "--friction");
    }
    TF_RETURN_IF_ERROR(api::ApplyFrictionEstimate(friction, "--friction", request));
  }
  return absl::OkStatus();
}

// The picture, written to a temporary name and renamed when complete
// (io::WriteTextFile); errors name --plot.
absl::Status WritePlot(const std::string& path, const absl::StatusOr<std::string>& svg) {
  if (!svg.ok()) return io::PrependPath(svg.status(), "--plot");
  if (absl::Status written = io::WriteTextFile(path, *svg); !written.ok()) {
    return io::PrependPath(written, "--plot");
  }
  return absl::OkStatus();
}

// One line per step (status, normal forces, solve time) and the totals.
std::string FormatTrajectoryTable(const v1::TrajectoryResponse& response) {
  std::string out = absl::StrFormat("%5s  %-14s  %-40s  %9s\n", "step", "status",
                                    "normal forces (N)", "time (us)");
  for (int k = 0; k < response.steps_size(); ++k) {
    const v1::PlanResponse& step = response.steps(k);
    std::string normals;
    for (double f : step.normal_forces()) absl::StrAppend(&normals, absl::StrFormat("%7.3f ", f));
    absl::StrAppendFormat(&out, "%5d  %-14s  %-40s  %9d\n", k, api::StatusName(step.status()),
                          normals, step.solve_time_us());
  }
  absl::StrAppendFormat(&out, "%d steps: %d optimal, %d infeasible, %d failed; total %d us\n",
                        response.steps_size(), response.optimal_steps(),
                        response.infeasible_steps(), response.failed_steps(),
                        response.total_time_us());
  return out;
}

// A request file with a `plan` (TrajectoryRequest, FrictionProbeRequest),
// the solver flags applied to it; errors name `flag` or the file.
template <class Request>
absl::StatusOr<Request> ReadPlanningRequest(const PlanArgs& args, const std::string& path,
                                            const std::string& flag) {
  TF_ASSIGN_OR_RETURN(std::string text, ReadInput(path, flag));
  Request request;
  TF_RETURN_IF_ERROR(api::ParseJson(text, &request, InputName(path)));
  ApplySolverFlags(args, request.mutable_plan());
  return request;
}

// --trajectory: the TrajectoryRequest planned by the backend.
int RunTrajectory(const PlanArgs& args) {
  absl::StatusOr<v1::TrajectoryRequest> request =
      ReadPlanningRequest<v1::TrajectoryRequest>(args, args.trajectory_path, "--trajectory");
  if (!request.ok()) return ReportError(request.status());
  absl::StatusOr<v1::TrajectoryResponse> response =
      CallBackend(args.backend, &Backend::PlanTrajectory, *request);
  if (!response.ok()) return ReportError(response.status());
  if (!args.plot_path.empty()) {
    const std::string name = InputName(args.trajectory_path);
    if (absl::Status s = WritePlot(args.plot_path, api::TrajectorySvg(*request, *response, name));
        !s.ok()) {
      return ReportError(s);
    }
  }
  std::cout << (args.output.json() ? api::ToJson(*response) : FormatTrajectoryTable(*response));
  return std::cout ? kExitOk : kExitFailure;
}

// One line per probe sample: time, the probe's force and the holding plan.
std::string FormatProbeTable(const v1::FrictionProbeResponse& response) {
  std::string out = absl::StrFormat("%5s  %8s  %-26s  %-14s  %s\n", "step", "t (s)",
                                    "probe force (N)", "holding", "holding normal forces (N)");
  for (int k = 0; k < response.times_size(); ++k) {
    const v1::Vec3& f = response.probe_forces(k);
    const v1::PlanResponse& step = k < response.holding().steps_size()
                                       ? response.holding().steps(k)
                                       : v1::PlanResponse::default_instance();
    std::string normals;
    for (double fn : step.normal_forces()) absl::StrAppend(&normals, absl::StrFormat("%7.3f ", fn));
    absl::StrAppendFormat(&out, "%5d  %8.3f  %8.3f %8.3f %8.3f  %-14s  %s\n", k, response.times(k),
                          f.x(), f.y(), f.z(), api::StatusName(step.status()), normals);
  }
  const v1::TrajectoryResponse& h = response.holding();
  absl::StrAppendFormat(&out, "%d samples: %d optimal, %d infeasible, %d failed; total %d us\n",
                        response.times_size(), h.optimal_steps(), h.infeasible_steps(),
                        h.failed_steps(), h.total_time_us());
  return out;
}

// --friction-probe: the FrictionProbeRequest planned by the backend.
int RunFrictionProbe(const PlanArgs& args) {
  absl::StatusOr<v1::FrictionProbeRequest> request =
      ReadPlanningRequest<v1::FrictionProbeRequest>(args, args.probe_path, "--friction-probe");
  if (!request.ok()) return ReportError(request.status());
  absl::StatusOr<v1::FrictionProbeResponse> response =
      CallBackend(args.backend, &Backend::PlanFrictionProbe, *request);
  if (!response.ok()) return ReportError(response.status());
  std::cout << (args.output.json() ? api::ToJson(*response) : FormatProbeTable(*response));
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace

CLI::App* AddPlanCommand(CLI::App& app, PlanArgs& args) {
  CLI::App* cmd = app.add_subcommand("plan", "Plan contact forces for one request");
  AddBackendFlags(cmd, &args.backend, "Planner.Plan, PlanTrajectory, PlanFrictionProbe");
  CLI::Option* request =
      cmd->add_option("--request", args.request_path,
                      "PlanRequest as JSON (proto field names, snake_case or lowerCamelCase); "
                      "- reads standard input")
          ->type_name("FILE");
  CLI::Option* trajectory =
      cmd->add_option(
             "--trajectory", args.trajectory_path,
             "TrajectoryRequest as JSON (plan + steps): one PlanResponse per step plus totals")
          ->type_name("FILE");
  request->excludes(trajectory);
  CLI::Option* probe =
      cmd->add_option("--friction-probe", args.probe_path,
                      "FrictionProbeRequest as JSON (plan = the holding grasp, the probe's "
                      "position, normal, "
                      "tangent, tangential force and normal-force ramp): the probe's force and the "
                      "holding plan "
                      "per sample (Planner.PlanFrictionProbe); - reads standard input")
          ->type_name("FILE");
  probe->excludes(request)->excludes(trajectory);
  AddOutputFlags(cmd, &args.output, "the PlanResponse (TrajectoryResponse, FrictionProbeResponse)");
  AddSolverFlags(cmd, &args);
  cmd->add_option(
         "--inertia", args.inertia_path,
         "FitInertiaResponse JSON (`tactforce inertia --json`): the object's mass, CoM and inertia "
         "and "
         "their covariance; the plan holds for every value within the request's confidence")
      ->type_name("FIT.json")
      ->excludes(trajectory)
      ->excludes(probe);
  cmd->add_option("--friction", args.friction_path,
                  "FrictionResponse JSON (`tactforce friction --json`): every fingertip contact's "
                  "friction = "
                  "its median, friction_sigma = its mu_sigma")
      ->type_name("FRICTION.json")
      ->excludes(trajectory)
      ->excludes(probe);
  cmd->add_option(
         "--plot", args.plot_path,
         "Also draw the plan as SVG: contacts, normals, robust friction cones, forces (arrows), "
         "their 1-sigma spread, CoM and gravity in three orthographic views (x-y, x-z, y-z). "
         "With --trajectory: small multiples, one panel per step (at most " +
             std::to_string(api::kMaxPlotSteps) + ", evenly subsampled and named in the figure)")
      ->type_name("FILE.svg")
      ->excludes(probe);
  cmd->footer(
      "Plans in this process, or on tactforce-server with --server ADDR. Exit status:\n"
      "0 when a plan was computed (optimal, infeasible or solver failure; see its\n"
      "status), 2 for bad input (the message names the field), 3 when the server\n"
      "cannot be reached, 4 when it did not answer within --deadline-ms, 1 otherwise.\n"
      "Examples:\n"
      "  tactforce plan --local --request client/examples/sphere_pinch.json\n"
      "  tactforce plan --local --request client/examples/sphere_pinch.json --solver cross-check "
      "--json\n"
      "  tactforce plan --server localhost:50051 --request client/examples/sphere_pinch.json "
      "--plot plan.svg\n"
      "  tactforce plan --local --trajectory client/examples/wrench_lift_trajectory.json\n"
      "  tactforce plan --local --friction-probe client/examples/friction_probe.json\n"
      "  tactforce plan --local --request grasp.json --inertia fit.json --friction friction.json");
  return cmd;
}

int RunPlan(const PlanArgs& args) {
  if (absl::Status s = CheckPlotPath(args.plot_path); !s.ok()) return ReportError(s);
  if (!args.trajectory_path.empty()) return RunTrajectory(args);
  if (!args.probe_path.empty()) return RunFrictionProbe(args);
  if (args.request_path.empty()) {
    return ReportError(absl::InvalidArgumentError(
        "give --request FILE, --trajectory FILE or --friction-probe FILE"));
  }
  absl::StatusOr<std::unique_ptr<Backend>> backend = MakeBackend(args.backend);
  if (!backend.ok()) return ReportError(backend.status());

  absl::StatusOr<std::string> text = ReadInput(args.request_path);
  if (!text.ok()) return ReportError(text.status());

  absl::StatusOr<v1::PlanRequest> request =
      api::ParsePlanRequestJson(*text, InputName(args.request_path));
  if (!request.ok()) return ReportError(request.status());
  ApplySolverFlags(args, &*request);
  if (absl::Status s = ApplyEstimateFlags(args, &*request); !s.ok()) return ReportError(s);

  absl::StatusOr<v1::PlanResponse> response = (*backend)->Plan(*request);
  if (!response.ok()) return ReportError(response.status());
  if (!args.plot_path.empty()) {
    if (absl::Status s = WritePlot(args.plot_path,
                                   api::PlanSvg(*request, *response, InputName(args.request_path)));
        !s.ok())
      return ReportError(s);
  }

  if (args.output.json()) {
    std::cout << api::ToJson(*response);
  } else {
    std::cout << api::FormatPlanTable(*request, *response);
  }
  std::cout.flush();
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace tactforce::cli
