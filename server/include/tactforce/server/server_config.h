// Command-line configuration of tactforce-server (CLI11).
#pragma once

#include <cstdint>
#include <string>

#include "CLI/CLI.hpp"
#include "tactforce/server/estimator_service.h"
#include "tactforce/server/planner_service.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/stream_registry.h"

namespace tactforce::server {

struct ServerConfig {
  std::string listen = "127.0.0.1:50051";
  int workers = 0;  // 0 = std::thread::hardware_concurrency()
  int ipopt_workers = 1;  // the Ipopt lane's threads (Ipopt runs one solve at a time per process)
  int queue = 64;   // solves waiting for a worker, beyond which RESOURCE_EXHAUSTED
  int max_message_bytes = 4 << 20;
  int max_contacts = PlannerServiceOptions{}.max_contacts;
  int solve_timeout_ms = PlannerServiceOptions{}.solve_timeout_ms;
  int inline_max_contacts = PlannerServiceOptions{}.inline_max_contacts;
  int64_t max_inertia_samples = EstimatorServiceOptions{}.max_inertia_samples;  // per FitInertia stream
  int64_t max_trajectory_work = PlannerServiceOptions{}.max_trajectory_work;  // steps x contacts x cone sides
  int64_t max_audit_samples = EstimatorServiceOptions{}.max_audit_samples;  // per AuditModel request
  int max_streams = StreamLimits{}.max_streams;
  int stream_idle_timeout_ms = static_cast<int>(StreamLimits{}.idle_timeout.count());
  int64_t max_inflight_samples = StreamLimits{}.max_inflight_samples;
  int64_t max_inflight_bytes = StreamLimits{}.max_inflight_bytes;
  int64_t max_fit_bytes = EstimatorServiceOptions{}.max_fit_bytes;  // per FitInertia fit
  int max_streams_per_connection = ServerOptions{}.max_streams_per_connection;
  bool reflection = true;
  bool reuse_port = false;
  std::string tls_cert;
  std::string tls_key;
  std::string tls_client_ca;
  std::string log_level = "warn";
  int grace_ms = 10'000;

  int EffectiveWorkers() const;
  ServerOptions ToServerOptions() const;
  PlannerServiceOptions ToPlannerOptions() const;
  EstimatorServiceOptions ToEstimatorOptions() const;
  StreamLimits ToStreamLimits() const;
};

// Adds every flag (with its documentation and range checks) to `app`.
void RegisterFlags(CLI::App& app, ServerConfig* config);

}  // namespace tactforce::server
