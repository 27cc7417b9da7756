#include "demo_command.h"

#include <algorithm>
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/api/table.h"
#include "tactforce/planner/examples.h"
#include "tactforce/planner/solver.h"

namespace tactforce::cli {
namespace {

// One grasp's outcome: the cross-check response of its first solve, with the
// fastest times seen over all repeats.
struct DemoRow {
  planner::ExampleGrasp grasp;
  v1::PlanRequest request;  // for contact names
  v1::PlanResponse response;
  int64_t geometric_us = 0;
  int64_t ipopt_us = 0;
  double speed_ratio = 0.0;  // ipopt / geometric
};

absl::StatusOr<DemoRow> RunGrasp(const planner::ExampleGrasp& grasp, int repeat) {
  DemoRow row;
  row.grasp = grasp;
  row.request = api::ToRequest(grasp.problem, grasp.options, planner::SolverKind::kCrossCheck);
  for (int run = 0; run < repeat; ++run) {
    absl::StatusOr<planner::PlanResult> result =
        planner::Plan(grasp.problem, grasp.options, planner::SolverKind::kCrossCheck);
    if (!result.ok()) {
      return absl::Status(result.status().code(),
                          absl::StrCat(grasp.name, ": ", result.status().message()));
    }
    if (run == 0) {
      row.response = api::ToProto(*result);
      if (result->cross_check.has_value()) {
        row.geometric_us = result->cross_check->geometric_time_us;
        row.ipopt_us = result->cross_check->ipopt_time_us;
      }
    } else if (result->cross_check.has_value()) {
      row.geometric_us = std::min(row.geometric_us, result->cross_check->geometric_time_us);
      row.ipopt_us = std::min(row.ipopt_us, result->cross_check->ipopt_time_us);
    }
  }
  row.speed_ratio = static_cast<double>(row.ipopt_us) /
                    static_cast<double>(std::max<int64_t>(row.geometric_us, 1));
  return row;
}

std::string AgreeText(const v1::PlanResponse& response) {
  if (!response.has_cross_check()) return "n/a";
  return response.cross_check().agree() ? "yes" : "NO";
}

std::string FormatTable(const std::vector<DemoRow>& rows, int repeat, double tolerance) {
  std::string out = absl::StrFormat(
      "tactforce demo: %d built-in grasps, geometric planner (FE-plane QP) vs Ipopt "
      "reference; times are the fastest of %d run%s\n",
      rows.size(), repeat, repeat == 1 ? "" : "s");
  for (const DemoRow& row : rows) {
    const v1::PlanResponse& r = row.response;
    absl::StrAppendFormat(&out, "\n== %s: %s\n", row.grasp.name, row.grasp.description);
    absl::StrAppendFormat(&out, "status %s", api::StatusName(r.status()));
    if (!r.message().empty()) absl::StrAppendFormat(&out, " (%s)", r.message());
    out += "\n";
    absl::StrAppendFormat(&out, "  %-12s %10s %10s %10s %10s\n", "finger", "fx [N]", "fy [N]",
                          "fz [N]", "normal [N]");
    for (int i = 0; i < r.forces_size(); ++i) {
      const std::string name = i < row.request.contacts_size() && !row.request.contacts(i).name().empty()
                                   ? row.request.contacts(i).name()
                                   : absl::StrCat("#", i);
      const double fn = i < r.normal_forces_size() ? r.normal_forces(i) : 0.0;
      absl::StrAppendFormat(&out, "  %-12s %10.4f %10.4f %10.4f %10.4f\n", name, r.forces(i).x(),
                            r.forces(i).y(), r.forces(i).z(), fn);
    }
    absl::StrAppendFormat(&out, "  objective %.6g N^2, min margin %.6g N\n", r.objective(),
                          r.min_margin());
    if (r.has_cross_check()) {
      const v1::CrossCheck& cc = r.cross_check();
      absl::StrAppendFormat(&out,
                            "  geometric %d us, ipopt %d us (%s): %.1fx faster; "
                            "max |df| %.2g N -> agree: %s\n",
                            row.geometric_us, row.ipopt_us, api::StatusName(cc.ipopt_status()),
                            row.speed_ratio, cc.max_force_diff(), AgreeText(r));
    } else {
      out += "  no cross-check report\n";
    }
  }

  out += "\nsummary\n";
  absl::StrAppendFormat(&out, "  %-14s %-11s %10s %10s %9s %12s %6s\n", "grasp", "status",
                        "geom [us]", "ipopt [us]", "speed-up", "max|df| [N]", "agree");
  int agreeing = 0;
  for (const DemoRow& row : rows) {
    const v1::PlanResponse& r = row.response;
    const bool cc = r.has_cross_check();
    if (cc && r.cross_check().agree()) ++agreeing;
    absl::StrAppendFormat(&out, "  %-14s %-11s %10d %10d %8.1fx %12s %6s\n", row.grasp.name,
                          api::StatusName(r.status()), row.geometric_us, row.ipopt_us,
                          row.speed_ratio,
                          cc ? absl::StrFormat("%.2g", r.cross_check().max_force_diff())
                             : std::string("-"),
                          AgreeText(r));
  }
  absl::StrAppendFormat(&out, "%d of %d grasps agree (max |df| <= %g N)\n", agreeing,
                        rows.size(), tolerance);
  return out;
}

std::string FormatJson(const std::vector<DemoRow>& rows, int repeat) {
  std::string out = absl::StrFormat("{\n  \"repeat\": %d,\n  \"grasps\": [", repeat);
  for (size_t i = 0; i < rows.size(); ++i) {
    const DemoRow& row = rows[i];
    absl::StrAppendFormat(
        &out,
        "%s\n    {\"name\": %s, \"description\": %s, \"geometric_time_us\": %d, "
        "\"ipopt_time_us\": %d, \"speed_ratio\": %.6g,\n     \"response\": %s}",
        i == 0 ? "" : ",", api::JsonQuote(row.grasp.name), api::JsonQuote(row.grasp.description),
        row.geometric_us, row.ipopt_us, row.speed_ratio,
        api::ToJson(row.response, /*compact=*/true));
  }
  out += "\n  ]\n}\n";
  return out;
}

}  // namespace

CLI::App* AddDemoCommand(CLI::App& app, DemoArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "demo", "Plan the built-in grasps with the geometric planner and Ipopt and compare");
  cmd->add_option("--format", args.format, "Output: table or json")
      ->check(CLI::IsMember({"table", "json"}))
      ->capture_default_str();
  cmd->add_option("--repeat", args.repeat, "Solves per grasp; the fastest times are shown")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->footer(
      "Solves every built-in grasp with the cross-check backend (geometric answer +\n"
      "Ipopt reference). Exit status: 0 when every grasp was planned (agreement is\n"
      "reported, not enforced), 1 on an internal error.");
  return cmd;
}

int RunDemo(const DemoArgs& args) {
  const std::vector<planner::ExampleGrasp> grasps = planner::BuiltInGrasps();
  std::vector<DemoRow> rows;
  rows.reserve(grasps.size());
  double tolerance = planner::PlanOptions().agreement_tolerance;
  for (const planner::ExampleGrasp& grasp : grasps) {
    absl::StatusOr<DemoRow> row = RunGrasp(grasp, args.repeat);
    // The built-in grasps are valid by construction: an error here is a bug.
    if (!row.ok()) {
      ReportError(row.status());
      return kExitFailure;
    }
    tolerance = grasp.options.agreement_tolerance;
    rows.push_back(*std::move(row));
  }
  std::cout << (args.format == "json" ? FormatJson(rows, args.repeat)
                                      : FormatTable(rows, args.repeat, tolerance));
  std::cout.flush();
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace tactforce::cli
