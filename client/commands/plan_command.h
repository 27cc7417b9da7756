// `tactforce plan`: one request (JSON file or stdin) -> one plan, computed in
// this process (the default, --local) or by tactforce-server (--server ADDR):
// a PlanRequest (--request), a TrajectoryRequest (--trajectory) or a
// FrictionProbeRequest (--friction-probe, Planner.PlanFrictionProbe).
#pragma once

#include <optional>
#include <string>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "backend.h"

namespace tactforce::cli {

struct PlanArgs {
  BackendArgs backend;          // --local | --server ADDR, --tls-*, --deadline-ms
  std::string request_path;     // "-" = stdin
  std::string trajectory_path;  // TrajectoryRequest JSON instead of --request
  std::string probe_path;       // FrictionProbeRequest JSON instead of --request
  OutputFormat output;          // table (default) | json
  // Solver overrides of the request (absent: the request's own values).
  std::string solver;  // geometric | ipopt | cross-check
  std::optional<double> ipopt_tolerance, ipopt_max_seconds, rank_tolerance, agreement_tolerance;
  std::optional<int> max_iterations;
  std::string plot_path;      // --plot: an SVG picture of the plan (or trajectory) too
  std::string inertia_path;   // --inertia: a FitInertiaResponse JSON (`inertia --json`)
  std::string friction_path;  // --friction: a FrictionResponse JSON (`friction --json`)
};

CLI::App* AddPlanCommand(CLI::App& app, PlanArgs& args);
int RunPlan(const PlanArgs& args);

}  // namespace tactforce::cli
