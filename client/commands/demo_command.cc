// `tactforce demo`: every built-in grasp planned here with the cross-check
// backend (geometric vs Ipopt, fastest of --repeat), and with --server the
// same grasps through tactforce-server (health, answers compared with the
// local ones, geometric round trips) and a short load test; tables or JSON.
#include "demo_command.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/ascii.h"
#include "cli_common.h"
#include "health_check.h"
#include "load/load_generator.h"
#include "backend.h"
#include "remote_call.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/api/names.h"
#include "tactforce/api/table.h"
#include "tactforce/planner/examples.h"
#include "tactforce/planner/solver.h"
#include "tactforce/io/json.h"
#include "tactforce/io/status_macros.h"

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
      return io::PrependPath(result.status(), grasp.name);
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
      const std::string name =
          i < row.request.contacts_size() && !row.request.contacts(i).name().empty()
              ? row.request.contacts(i).name()
              : absl::StrCat("#", i);
      const double fn = i < r.normal_forces_size() ? r.normal_forces(i) : 0.0;
      absl::StrAppendFormat(&out, "  %-12s %10.4f %10.4f %10.4f %10.4f\n", name, r.forces(i).x(),
                            r.forces(i).y(), r.forces(i).z(), fn);
    }
    if (r.status() == v1::PLAN_STATUS_OPTIMAL)
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
    absl::StrAppendFormat(
        &out, "  %-14s %-11s %10d %10d %8.1fx %12s %6s\n", row.grasp.name,
        api::StatusName(r.status()), row.geometric_us, row.ipopt_us, row.speed_ratio,
        cc ? absl::StrFormat("%.2g", r.cross_check().max_force_diff()) : std::string("-"),
        AgreeText(r));
  }
  absl::StrAppendFormat(&out, "%d of %d grasps agree (max |df| <= %g N)\n", agreeing, rows.size(),
                        tolerance);
  return out;
}

std::string FormatJson(const std::vector<DemoRow>& rows, int repeat,
                       const std::string& server_json) {
  std::string out = absl::StrFormat("{\n  \"repeat\": %d,\n  \"grasps\": [", repeat);
  for (size_t i = 0; i < rows.size(); ++i) {
    const DemoRow& row = rows[i];
    absl::StrAppendFormat(&out,
                          "%s\n    {\"name\": %s, \"description\": %s, \"geometric_time_us\": %d, "
                          "\"ipopt_time_us\": %d, \"speed_ratio\": %.6g,\n     \"response\": %s}",
                          i == 0 ? "" : ",", io::JsonEscape(row.grasp.name),
                          io::JsonEscape(row.grasp.description), row.geometric_us, row.ipopt_us,
                          row.speed_ratio, api::ToJson(row.response, /*compact=*/true));
  }
  out += "\n  ]";
  if (!server_json.empty()) absl::StrAppend(&out, ",\n  \"server\": ", server_json);
  out += "\n}\n";
  return io::IndentJson(out);  // the embedded compact responses laid out too
}

// ------------------------------------------------------------ --server

// One grasp planned by the server: the cross-check answer compared with the
// local one, and the fastest round trip of a geometric-only call.
struct RemoteRow {
  std::string name;
  v1::PlanResponse response;       // cross-check solve on the server
  double max_diff_vs_local = 0.0;  // N, max abs force component difference
  bool match = false;              // same status and forces (<= kMatchTolerance)
  int64_t geometric_round_trip_us = 0;
  int64_t geometric_server_us = 0;  // the server's solve_time_us of that call
};

// Same binary code on both sides: the answers should be identical; the
// tolerance only absorbs printing/parsing, of which there is none.
constexpr double kMatchTolerance = 1e-9;

struct RemoteResult {
  std::string address;
  std::string health;          // whole server
  std::string planner_health;  // tactforce.v1.Planner
  std::vector<RemoteRow> rows;
  bool has_load = false;
  LoadReport load;
};

double MaxForceDiff(const v1::PlanResponse& a, const v1::PlanResponse& b) {
  if (a.forces_size() != b.forces_size()) return INFINITY;
  double diff = 0.0;
  for (int i = 0; i < a.forces_size(); ++i) {
    diff = std::max({diff, std::abs(a.forces(i).x() - b.forces(i).x()),
                     std::abs(a.forces(i).y() - b.forces(i).y()),
                     std::abs(a.forces(i).z() - b.forces(i).z())});
  }
  return diff;
}

absl::StatusOr<RemoteResult> RunRemote(const DemoArgs& args, const std::vector<DemoRow>& local) {
  ConnectionArgs connection = args.connection;
  connection.server = args.server;
  RemoteResult result;
  result.address = args.server;

  TF_ASSIGN_OR_RETURN(RemoteServer server, RemoteServer::Open(connection));
  TF_ASSIGN_OR_RETURN(result.health, CheckHealth(server, ""));
  TF_ASSIGN_OR_RETURN(result.planner_health, CheckHealth(server, "tactforce.v1.Planner"));

  TF_ASSIGN_OR_RETURN(std::unique_ptr<Backend> backend, MakeRemoteBackend(connection));
  for (const DemoRow& row : local) {
    RemoteRow remote;
    remote.name = row.grasp.name;
    TF_ASSIGN_OR_RETURN(v1::PlanResponse response, backend->Plan(row.request));
    remote.response = std::move(response);
    remote.max_diff_vs_local = MaxForceDiff(remote.response, row.response);
    remote.match = remote.response.status() == row.response.status() &&
                   remote.max_diff_vs_local <= kMatchTolerance;

    v1::PlanRequest geometric = row.request;
    geometric.set_solver(v1::SOLVER_GEOMETRIC);
    for (int run = 0; run < std::max(args.repeat, 1); ++run) {
      const auto start = std::chrono::steady_clock::now();
      absl::StatusOr<v1::PlanResponse> fast = backend->Plan(geometric);
      const int64_t us = std::chrono::duration_cast<std::chrono::microseconds>(
                             std::chrono::steady_clock::now() - start)
                             .count();
      if (!fast.ok()) return fast.status();
      if (run == 0 || us < remote.geometric_round_trip_us) {
        remote.geometric_round_trip_us = us;
        remote.geometric_server_us = fast->solve_time_us();
      }
    }
    result.rows.push_back(std::move(remote));
  }

  if (args.load_seconds > 0) {
    LoadSpec spec;
    spec.rpc = LoadRpc::kPlan;
    spec.concurrency = args.load_concurrency;
    spec.duration_s = args.load_seconds;
    spec.deadline_ms = connection.deadline_ms;
    spec.requests = RandomRequestMix(/*seed=*/1, /*count=*/256);
    TF_ASSIGN_OR_RETURN(std::vector<std::shared_ptr<grpc::Channel>> channels,
                        ConnectLoadChannels(connection, connection.server, /*per_target=*/1, spec));
    TF_ASSIGN_OR_RETURN(LoadReport load, RunLoad(spec, channels));
    result.has_load = true;
    result.load = std::move(load);
  }
  return result;
}

std::string FormatRemoteTable(const RemoteResult& r, const DemoArgs& args) {
  std::string out = absl::StrFormat("\nserver %s\n", r.address);
  absl::StrAppendFormat(&out, "  health: %s (tactforce.v1.Planner: %s)\n", r.health,
                        r.planner_health);
  absl::StrAppendFormat(
      &out,
      "  the same grasps planned by the server (cross-check), compared with the local "
      "answers;\n  geometric-only round trip: fastest of %d call%s\n",
      args.repeat, args.repeat == 1 ? "" : "s");
  absl::StrAppendFormat(&out, "  %-14s %-11s %6s %14s %6s %13s %12s\n", "grasp", "status", "agree",
                        "|df| vs local", "match", "round trip", "server solve");
  absl::StrAppendFormat(&out, "  %-14s %-11s %6s %14s %6s %13s %12s\n", "", "", "", "[N]", "",
                        "[us]", "[us]");
  int matching = 0;
  for (const RemoteRow& row : r.rows) {
    if (row.match) ++matching;
    absl::StrAppendFormat(&out, "  %-14s %-11s %6s %14.2g %6s %13d %12d\n", row.name,
                          api::StatusName(row.response.status()), AgreeText(row.response),
                          row.max_diff_vs_local, row.match ? "yes" : "NO",
                          row.geometric_round_trip_us, row.geometric_server_us);
  }
  absl::StrAppendFormat(&out, "%d of %d server answers match the local ones\n", matching,
                        r.rows.size());
  if (r.has_load) {
    absl::StrAppendFormat(&out,
                          "\nload test: %.0f s of unary Plan calls (random geometric grasps)\n",
                          args.load_seconds);
    out += FormatLoadText(r.load, r.address);
  }
  return out;
}

std::string FormatRemoteJson(const RemoteResult& r) {
  std::string out = absl::StrFormat(
      "{\"address\": %s, \"health\": %s, \"planner_health\": %s, \"grasps\": [",
      io::JsonEscape(r.address), io::JsonEscape(r.health), io::JsonEscape(r.planner_health));
  for (size_t i = 0; i < r.rows.size(); ++i) {
    const RemoteRow& row = r.rows[i];
    absl::StrAppendFormat(
        &out,
        "%s\n    {\"name\": %s, \"match\": %s, \"max_force_diff_vs_local\": %.6g, "
        "\"geometric_round_trip_us\": %d, \"geometric_server_us\": %d,\n     "
        "\"response\": %s}",
        i == 0 ? "" : ",", io::JsonEscape(row.name), row.match ? "true" : "false",
        row.max_diff_vs_local, row.geometric_round_trip_us, row.geometric_server_us,
        api::ToJson(row.response, /*compact=*/true));
  }
  out += "\n  ]";
  if (r.has_load) {
    std::string load = FormatLoadJson(r.load, r.address);
    absl::StripTrailingAsciiWhitespace(&load);
    absl::StrAppend(&out, ",\n  \"load\": ", load);
  }
  out += "}";
  return out;
}

}  // namespace

CLI::App* AddDemoCommand(CLI::App& app, DemoArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "demo", "Plan the built-in grasps with the geometric planner and Ipopt and compare");
  AddOutputFlags(cmd, &args.output, "the comparison");
  cmd->add_option("--repeat", args.repeat, "Solves per grasp; the fastest times are shown")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  cmd->add_option("--server", args.server,
                  "Also run the grasps through tactforce-server at this address: health, "
                  "the same plans checked against the local answers, and a load test")
      ->type_name("ADDR");
  AddConnectionFlags(cmd, &args.connection, /*server_flag=*/"");
  cmd->add_option("--load-seconds", args.load_seconds,
                  "Length of the load test against --server (0 = skip it)")
      ->check(CLI::Range(0.0, 3600.0))
      ->capture_default_str();
  cmd->add_option("--load-concurrency", args.load_concurrency,
                  "Calls in flight during the load test")
      ->check(CLI::Range(1, 10'000))
      ->capture_default_str();
  cmd->footer(
      "Solves every built-in grasp with the cross-check backend (geometric answer +\n"
      "Ipopt reference). With --server, the server must be SERVING, answer every\n"
      "grasp exactly as this process did, and the load test must have no failed call.\n"
      "Exit status: 0 when all of that holds (Ipopt agreement is reported, not\n"
      "enforced); 3 when the server cannot be reached or is not serving, 4 when it\n"
      "did not answer within --deadline-ms, 1 otherwise. Examples:\n"
      "  tactforce demo\n"
      "  tactforce demo --server localhost:50051 --load-seconds 3 --json");
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
  if (args.server.empty()) {
    std::cout << (args.output.json() ? FormatJson(rows, args.repeat, "")
                                     : FormatTable(rows, args.repeat, tolerance));
    std::cout.flush();
    return std::cout ? kExitOk : kExitFailure;
  }

  // The local table first, so that it is there even if the server is not.
  if (!args.output.json()) {
    std::cout << FormatTable(rows, args.repeat, tolerance) << std::flush;
  }
  absl::StatusOr<RemoteResult> remote = RunRemote(args, rows);
  if (!remote.ok()) return ReportError(remote.status());
  std::cout << (args.output.json() ? FormatJson(rows, args.repeat, FormatRemoteJson(*remote))
                                   : FormatRemoteTable(*remote, args));
  std::cout.flush();
  if (!std::cout) return kExitFailure;

  if (remote->health != "SERVING" || remote->planner_health != "SERVING") {
    std::cerr << "error: " << remote->address << " is not serving" << std::endl;
    return kExitUnavailable;
  }
  for (const RemoteRow& row : remote->rows) {
    if (!row.match) {
      std::cerr << "error: " << remote->address << " answered " << row.name
                << " differently from this process" << std::endl;
      return kExitFailure;
    }
  }
  if (remote->has_load && remote->load.ok != remote->load.requests) {
    std::cerr << "error: load test: " << (remote->load.requests - remote->load.ok) << " of "
              << remote->load.requests << " calls failed" << std::endl;
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace tactforce::cli
