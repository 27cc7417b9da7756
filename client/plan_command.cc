// `tactforce plan`: one PlanRequest through a PlanBackend (local or
// remote), or a TrajectoryRequest (--trajectory) planned here or through
// Planner.PlanTrajectory; JSON or a table out.
#include "plan_command.h"

#include <iostream>
#include <memory>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "plan_backend.h"
#include "remote_call.h"
#include "tactforce/api/json.h"
#include "tactforce/api/names.h"
#include "tactforce/api/services.h"
#include "tactforce/api/table.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::cli {
namespace {

absl::StatusOr<std::unique_ptr<PlanBackend>> SelectBackend(const PlanArgs& args) {
  if (args.local) return MakeLocalBackend();
  return MakeRemoteBackend(args.connection);
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

// --trajectory: the TrajectoryRequest planned here (--local) or by the server.
int RunTrajectory(const PlanArgs& args) {
  absl::StatusOr<std::string> text = ReadInput(args.trajectory_path, "--trajectory");
  if (!text.ok()) return ReportError(text.status());
  v1::TrajectoryRequest request;
  if (absl::Status s = api::ParseJson(*text, &request, "trajectory JSON"); !s.ok()) return ReportError(s);
  absl::StatusOr<v1::TrajectoryResponse> response =
      args.local ? api::HandleTrajectory(request)
                 : CallUnary(args.connection, &v1::Planner::Stub::PlanTrajectory, request);
  if (!response.ok()) return ReportError(response.status());
  std::cout << (args.format == "table" ? FormatTrajectoryTable(*response) : api::ToJson(*response));
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace

CLI::App* AddPlanCommand(CLI::App& app, PlanArgs& args) {
  CLI::App* cmd = app.add_subcommand("plan", "Plan contact forces for one request");
  CLI::Option* local = cmd->add_flag("--local", args.local, "Plan in this process (no server)");
  CLI::Option* server = AddConnectionFlags(cmd, &args.connection);
  local->excludes(server);
  CLI::Option* request =
      cmd->add_option("--request", args.request_path,
                      "PlanRequest as JSON (proto field names, snake_case or lowerCamelCase); "
                      "- reads standard input")
          ->type_name("FILE");
  CLI::Option* trajectory =
      cmd->add_option("--trajectory", args.trajectory_path,
                      "TrajectoryRequest as JSON (plan + steps): one PlanResponse per step plus totals")
          ->type_name("FILE");
  request->excludes(trajectory);
  cmd->add_option("--format", args.format, "Output: json (PlanResponse) or table")
      ->check(CLI::IsMember({"json", "table"}))
      ->capture_default_str();
  cmd->footer(
      "Sends the request to tactforce-server (--server, default " + std::string(kDefaultServer) +
      ") unless\n"
      "--local is given. Exit status: 0 when a plan was computed (optimal, infeasible\n"
      "or solver failure; see its status), 2 for bad input (the message names the\n"
      "field), 3 when the server cannot be reached, 4 when it did not answer within\n"
      "--deadline-ms, 1 otherwise.");
  return cmd;
}

int RunPlan(const PlanArgs& args) {
  if (!args.trajectory_path.empty()) return RunTrajectory(args);
  if (args.request_path.empty()) {
    return ReportError(absl::InvalidArgumentError("give --request FILE or --trajectory FILE"));
  }
  absl::StatusOr<std::unique_ptr<PlanBackend>> backend = SelectBackend(args);
  if (!backend.ok()) return ReportError(backend.status());

  absl::StatusOr<std::string> text = ReadInput(args.request_path);
  if (!text.ok()) return ReportError(text.status());

  absl::StatusOr<v1::PlanRequest> request = api::ParsePlanRequestJson(*text);
  if (!request.ok()) return ReportError(request.status());

  absl::StatusOr<v1::PlanResponse> response = (*backend)->Plan(*request);
  if (!response.ok()) return ReportError(response.status());

  if (args.format == "table") {
    std::cout << api::FormatPlanTable(*request, *response);
  } else {
    std::cout << api::ToJson(*response);
  }
  std::cout.flush();
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace tactforce::cli
