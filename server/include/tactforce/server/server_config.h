// Command-line configuration of tactforce-server (CLI11).
#pragma once

#include <cstdint>
#include <string>

#include "CLI/CLI.hpp"
#include "tactforce/api/dispatch.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/services.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/stream_registry.h"

namespace tactforce::server {

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";
  int workers = 0;        // 0 = std::thread::hardware_concurrency()
  int ipopt_workers = 1;  // the Ipopt lane's threads (Ipopt runs one solve at a time per process)
  int queue = 64;         // solves waiting for a worker, beyond which RESOURCE_EXHAUSTED
  // The limits of every call, filled by the flags: --max-contacts,
  // --max-trajectory-work, --max-audit-samples, --max-fit-bytes,
  // --max-message-bytes (max_response_bytes, also the transport's limit) and
  // --solve-timeout-ms (solve_timeout_ms: the work budget and Ipopt's CPU cap).
  api::CallLimits limits = DefaultCallLimits();
  int inline_max_contacts = api::PlanSettings{}.inline_max_contacts;
  int64_t max_inertia_samples = api::kDefaultMaxInertiaSamples;  // per FitInertia stream
  int max_streams = StreamLimits{}.max_streams;
  int stream_idle_timeout_ms = static_cast<int>(StreamLimits{}.idle_timeout.count());
  int64_t max_inflight_samples = StreamLimits{}.max_inflight_samples;
  int64_t max_inflight_bytes = StreamLimits{}.max_inflight_bytes;
  int max_streams_per_connection = ServerOptions{}.max_streams_per_connection;
  bool reflection = true;
  bool reuse_port = false;
  std::string tls_cert;
  std::string tls_key;
  std::string tls_client_ca;
  std::string log_level = "warn";
  int grace_ms = 10'000;

  // The server's defaults: api's, with a 4 MiB message limit, 10 s of work
  // per call and 256 MiB per inertia fit.
  static api::CallLimits DefaultCallLimits();
  // --solve-timeout-ms: the one place milliseconds become limits' seconds.
  void SetSolveTimeoutMs(int ms);
  int solve_timeout_ms() const;

  int EffectiveWorkers() const;
  ServerOptions ToServerOptions() const;
  api::PlanSettings ToPlanSettings() const;
  StreamLimits ToStreamLimits() const;
};

// Adds every flag (with its documentation and range checks) to `app`.
void RegisterFlags(CLI::App& app, ServerConfig* config);

}  // namespace tactforce::server
