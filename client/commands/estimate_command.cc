// `tactforce estimate`: the EstimateRequest file through the Backend,
// the response as JSON or one line per contact and per reading.
#include "estimate_command.h"

#include <iostream>

#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "tactforce/api/json.h"
#include "tactforce/api/names.h"

namespace tactforce::cli {

CLI::App* AddEstimateCommand(CLI::App& app, EstimateArgs& args) {
  CLI::App* cmd = app.add_subcommand("estimate", "Estimate contact forces from tactile readings");
  AddBackendFlags(cmd, &args.backend, "Estimator.EstimateForces");
  cmd->add_option("--request", args.request_path,
                  "EstimateRequest as JSON (object, contacts, readings, method, ...); - = stdin")
      ->required()
      ->type_name("FILE");
  AddOutputFlags(cmd, &args.output, "the EstimateResponse");
  cmd->footer(
      "Prints the force of every contact (request order, object frame, N) and the\n"
      "residual of every reading. Examples:\n"
      "  tactforce estimate --local --request client/examples/estimate_request.json\n"
      "  tactforce estimate --server localhost:50051 --request "
      "client/examples/estimate_request.json --json\n"
      "  cat client/examples/estimate_request.json | tactforce estimate --local --request -");
  return cmd;
}

namespace {

// One line per contact and per reading.
std::string FormatEstimateTable(const v1::EstimateRequest& request,
                                const v1::EstimateResponse& response) {
  std::string out =
      absl::StrFormat("status: %s%s%s  (method %s, %d us)\n", api::ShortEnumName(response.status()),
                      response.message().empty() ? "" : ": ", response.message(),
                      api::ShortEnumName(response.method()), response.solve_time_us());
  absl::StrAppendFormat(&out, "%-4s %-12s %10s %10s %10s %12s\n", "#", "contact", "fx (N)",
                        "fy (N)", "fz (N)", "normal (N)");
  for (int i = 0; i < response.forces_size(); ++i) {
    const v1::Vec3& f = response.forces(i);
    const std::string name = i < request.contacts_size() ? request.contacts(i).name() : "";
    absl::StrAppendFormat(&out, "%-4d %-12s %10.4f %10.4f %10.4f %12.4f\n", i, name, f.x(), f.y(),
                          f.z(),
                          i < response.normal_forces_size() ? response.normal_forces(i) : 0.0);
  }
  for (int k = 0; k < response.residuals_size(); ++k) {
    absl::StrAppendFormat(&out, "reading %d: residual %+.4f N\n", k, response.residuals(k));
  }
  return out;
}

}  // namespace

int RunEstimate(const EstimateArgs& args) {
  absl::StatusOr<std::string> text = ReadInput(args.request_path);
  if (!text.ok()) return ReportError(text.status());
  v1::EstimateRequest request;
  if (absl::Status s = api::ParseJson(*text, &request, InputName(args.request_path)); !s.ok())
    return ReportError(s);
  absl::StatusOr<v1::EstimateResponse> response =
      CallBackend(args.backend, &Backend::EstimateForces, request);
  if (!response.ok()) return ReportError(response.status());
  std::cout << (args.output.json() ? api::ToJson(*response)
                                   : FormatEstimateTable(request, *response));
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace tactforce::cli
