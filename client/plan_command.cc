#include "plan_command.h"

#include <iostream>
#include <memory>

#include "absl/status/statusor.h"
#include "cli_common.h"
#include "plan_backend.h"
#include "tactforce/api/json.h"
#include "tactforce/api/table.h"

namespace tactforce::cli {
namespace {

absl::StatusOr<std::unique_ptr<PlanBackend>> SelectBackend(const PlanArgs& args) {
  if (args.local) return MakeLocalBackend();
  return MakeRemoteBackend(args.connection);
}

}  // namespace

CLI::App* AddPlanCommand(CLI::App& app, PlanArgs& args) {
  CLI::App* cmd = app.add_subcommand("plan", "Plan contact forces for one request");
  CLI::Option* local = cmd->add_flag("--local", args.local, "Plan in this process (no server)");
  CLI::Option* server = AddConnectionFlags(cmd, &args.connection);
  local->excludes(server);
  cmd->add_option("--request", args.request_path,
                  "PlanRequest as JSON (proto field names, snake_case or lowerCamelCase); "
                  "- reads standard input")
      ->required()
      ->type_name("FILE");
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
