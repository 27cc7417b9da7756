// `tactforce load`: a load generator for tactforce-server (Plan, PlanStream,
// health, EstimateForces, FitInertia or AuditModel calls; closed or open
// loop; QPS, latency percentiles, errors by code; an optional SVG plot).
#pragma once

#include <cstdint>
#include <string>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "connection.h"

namespace tactforce::cli {

struct LoadArgs {
  ConnectionArgs connection;        // --target/--server (a list), --tls-*, --deadline-ms
  std::string rpc = "plan";         // plan | stream | health | estimate | fit-inertia | audit
  std::string engine = "callback";  // callback | sync
  int concurrency = 0;              // 0: 1 in closed loop, 1000 in open loop
  double rate = 0;                  // calls/s; 0 = closed loop
  int64_t requests = 0;             // 0 = no count bound
  double duration_s = 0;            // 0 = no time bound (default 10 s without --requests)
  std::string request_path;         // the RPC's request file; empty = the mix / built in
  bool mix = false;                 // the built-in random mix (default without --request)
  uint64_t seed = 1;
  int mix_size = 256;
  int batch = 0;          // fit-inertia CSV: samples per message; 0 = 500
  std::string service;    // health: service asked about
  int channels = 1;       // channels (connections) per target
  OutputFormat output;    // table (default) | json
  std::string plot_path;  // --plot: SVG of the run; empty = none
  bool progress = false;  // progress line on stderr even when not a TTY
};

CLI::App* AddLoadCommand(CLI::App& app, LoadArgs& args);
int RunLoadCommand(const LoadArgs& args);

}  // namespace tactforce::cli
