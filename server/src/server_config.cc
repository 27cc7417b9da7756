// ServerConfig (server_config.h): effective worker count, the options of
// the host and services, and the documented, range-checked flags.
#include "tactforce/server/server_config.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <string>
#include <thread>

namespace tactforce::server {

api::CallLimits ServerConfig::DefaultCallLimits() {
  api::CallLimits limits;
  limits.max_response_bytes = 4 << 20;
  limits.max_fit_bytes = int64_t{256} << 20;
  limits.solve_timeout_ms = 10'000;
  return limits;
}

void ServerConfig::SetSolveTimeoutMs(int ms) { limits.solve_timeout_ms = ms; }

int ServerConfig::solve_timeout_ms() const { return static_cast<int>(limits.solve_timeout_ms); }

int ServerConfig::EffectiveWorkers() const {
  if (workers > 0) return workers;
  return std::max(1, static_cast<int>(std::thread::hardware_concurrency()));
}

ServerOptions ServerConfig::ToServerOptions() const {
  ServerOptions options;
  options.listen = listen;
  options.max_message_bytes = static_cast<int>(limits.max_response_bytes);
  options.tls.cert = tls_cert;
  options.tls.key = tls_key;
  options.tls.client_ca = tls_client_ca;
  options.max_streams_per_connection = max_streams_per_connection;
  options.reflection = reflection;
  options.reuse_port = reuse_port;
  return options;
}

api::PlanSettings ServerConfig::ToPlanSettings() const {
  api::PlanSettings settings;
  settings.limits = limits;
  settings.inline_max_contacts = inline_max_contacts;
  return settings;
}

StreamLimits ServerConfig::ToStreamLimits() const {
  StreamLimits limits;
  limits.max_streams = max_streams;
  limits.idle_timeout = std::chrono::milliseconds(stream_idle_timeout_ms);
  limits.max_inflight_samples = max_inflight_samples;
  limits.max_inflight_bytes = max_inflight_bytes;
  return limits;
}

namespace {

// Where to listen and how many threads serve.
void RegisterListenAndWorkerFlags(CLI::App& app, ServerConfig* c) {
  app.add_option("--listen", c->listen,
                 "Address to listen on, host:port. Port 0 picks a free port; the bound "
                 "address is printed on stdout as 'tactforce-server listening on HOST:PORT'. "
                 "Listening on every interface must be asked for: 0.0.0.0:50051 or [::]:50051")
      ->type_name("HOST:PORT")
      ->check(CLI::Validator(
          [](std::string& address) -> std::string {
            if (address.rfind("unix:", 0) == 0) return "";
            const size_t colon = address.rfind(':');
            const std::string port = colon == std::string::npos ? "" : address.substr(colon + 1);
            int value = -1;
            if (port.empty() || port.size() > 5 ||
                port.find_first_not_of("0123456789") != std::string::npos ||
                (value = std::stoi(port)) > 65535) {
              return "'" + address + "': expected HOST:PORT with a port of 0..65535";
            }
            return "";
          },
          "HOST:PORT"));
  app.add_flag("--reuse-port", c->reuse_port,
               "Let several processes listen on the same port (SO_REUSEPORT, the kernel spreads "
               "connections over them); without it a port in use is a startup error (exit 1)");
  app.add_option("--workers", c->workers,
                 "Worker threads for large geometric solves, trajectories, estimation, inertia "
                 "fits and audits (0 = hardware threads); Ipopt work has its own lane "
                 "(--ipopt-workers)")
      ->check(CLI::Range(0, 1024));
  app.add_option(
         "--ipopt-workers", c->ipopt_workers,
         "Threads of the Ipopt lane: Plan, PlanStream, PlanTrajectory and PlanFrictionProbe "
         "requests with SOLVER_IPOPT or SOLVER_CROSS_CHECK run there, with their own queue of "
         "--queue, so geometric work never waits behind Ipopt (which runs one solve at a "
         "time per process: more than 1 only queues inside the process)")
      ->check(CLI::Range(1, 64));
  app.add_option("--queue", c->queue,
                 "Solves that may wait for a worker; beyond that requests fail with "
                 "RESOURCE_EXHAUSTED")
      ->check(CLI::Range(0, 1'000'000));
}

// The limits of one call.
void RegisterCallLimitFlags(CLI::App& app, ServerConfig* c) {
  app.add_option("--max-message-bytes", c->limits.max_response_bytes,
                 "Largest request or response message; bigger ones fail with RESOURCE_EXHAUSTED")
      ->check(CLI::Range(int64_t{1024}, int64_t{1} << 30));
  app.add_option("--max-contacts", c->limits.max_contacts,
                 "Most contacts a request may have (INVALID_ARGUMENT 'contacts: ...' beyond)")
      ->check(CLI::Range(1, 100'000));
  app.add_option(
         "--max-inertia-samples", c->max_inertia_samples,
         "Most samples one FitInertia stream may carry (INVALID_ARGUMENT 'samples: ...' beyond)")
      ->check(CLI::Range(int64_t{10}, int64_t{100'000'000}));
  app.add_option(
         "--max-trajectory-work", c->limits.max_trajectory_work,
         "Most steps x contacts x cone sides one PlanTrajectory or PlanFrictionProbe may ask "
         "for (INVALID_ARGUMENT 'steps: ...' beyond, before any solve)")
      ->check(CLI::Range(int64_t{1}, int64_t{1'000'000'000}));
  app.add_option_function<int>(
         "--solve-timeout-ms", [c](int ms) { c->SetSolveTimeoutMs(ms); },
         "Work limit of one call in ms (0 = none), counted from when its work starts "
         "(queue wait excluded): PlanTrajectory, PlanFrictionProbe, FitInertia, "
         "AuditModel, EstimateFriction and EstimateForces stop with RESOURCE_EXHAUSTED "
         "when they reach it; each Ipopt solve is capped to this much CPU time and "
         "then returns PLAN_STATUS_SOLVER_FAILURE")
      ->default_str(std::to_string(c->solve_timeout_ms()))
      ->check(CLI::Range(0, 3'600'000));
  app.add_option(
         "--max-audit-samples", c->limits.max_audit_samples,
         "Most samples one AuditModel request may carry (INVALID_ARGUMENT 'samples: ...' beyond)")
      ->check(CLI::Range(int64_t{40}, int64_t{100'000'000}));
}

// Limits of the streams, all together and per connection.
void RegisterStreamFlags(CLI::App& app, ServerConfig* c) {
  app.add_option("--max-streams", c->max_streams,
                 "Most PlanStream and FitInertia streams open at once on this server; a new one "
                 "beyond ends at once with RESOURCE_EXHAUSTED (0 = no limit)")
      ->check(CLI::Range(0, 10'000'000));
  app.add_option("--stream-idle-timeout-ms", c->stream_idle_timeout_ms,
                 "A PlanStream or FitInertia stream that waits longer than this for its next "
                 "message is ended with UNAVAILABLE (checked once a second; 0 = never)")
      ->check(CLI::Range(0, 86'400'000));
  app.add_option("--max-inflight-samples", c->max_inflight_samples,
                 "Most FitInertia samples all open streams may hold together (about 250 bytes "
                 "each); the message that would exceed it ends its stream with RESOURCE_EXHAUSTED "
                 "(0 = no limit)")
      ->check(CLI::Range(int64_t{0}, int64_t{1'000'000'000}));
  app.add_option(
         "--max-inflight-bytes", c->max_inflight_bytes,
         "Most bytes all open FitInertia streams may hold together (converted samples with "
         "their contacts, and the options with the mesh); the message that would exceed it "
         "ends its stream with RESOURCE_EXHAUSTED (0 = no limit). The default, 256 MiB, is a "
         "quarter of the shipped Kubernetes memory limit")
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 40));
  app.add_option(
         "--max-fit-bytes", c->limits.max_fit_bytes,
         "Most working memory one FitInertia fit may take, estimated from its method and "
         "sample count before it starts (FACTOR_GRAPH ~4.5 KB per sample, the others ~2 KB); "
         "a bigger fit is refused with INVALID_ARGUMENT naming the most samples it may have "
         "(0 = no limit)")
      ->check(CLI::Range(int64_t{0}, int64_t{1} << 40));
  app.add_option("--max-streams-per-connection", c->max_streams_per_connection,
                 "Calls one client connection may have in flight at once (HTTP/2 "
                 "SETTINGS_MAX_CONCURRENT_STREAMS); further calls wait in the client")
      ->check(CLI::Range(1, 1'000'000));
}

// Reflection, inline solves, TLS, logging and the drain.
void RegisterServiceFlags(CLI::App& app, ServerConfig* c) {
  app.add_flag("--reflection,!--no-reflection", c->reflection,
               "Serve gRPC server reflection (grpc.reflection.v1alpha), which lets tools such as "
               "grpcurl list and describe the services; --reflection=false or --no-reflection "
               "turns it off for production");
  app.add_option("--inline-max-contacts", c->inline_max_contacts,
                 "Geometric requests with at most this many contacts are solved on the gRPC "
                 "thread instead of the worker pool (0 = always use the pool)")
      ->check(CLI::Range(0, 100'000));
  auto* cert = app.add_option("--tls-cert", c->tls_cert,
                              "PEM certificate chain; enables TLS (needs --tls-key)")
                   ->check(CLI::ExistingFile);
  auto* key = app.add_option("--tls-key", c->tls_key, "PEM private key of --tls-cert")
                  ->check(CLI::ExistingFile);
  auto* ca = app.add_option("--tls-client-ca", c->tls_client_ca,
                            "PEM CA bundle; enables mutual TLS: clients must present a "
                            "certificate signed by it")
                 ->check(CLI::ExistingFile);
  cert->needs(key);
  key->needs(cert);
  ca->needs(cert);
  app.add_option("--log-level", c->log_level,
                 "Log level on stderr; 'info' logs one line per request "
                 "(rpc, code, solver, contacts, time)")
      ->check(CLI::IsMember({"off", "error", "warn", "info", "debug"}));
  app.add_option("--grace-ms", c->grace_ms,
                 "On SIGINT/SIGTERM: health Watch streams get NOT_SERVING, new calls (health Check "
                 "included) are refused with UNAVAILABLE and in-flight calls get this long to "
                 "finish before they are cancelled")
      ->check(CLI::Range(0, 3'600'000));
}

}  // namespace

void RegisterFlags(CLI::App& app, ServerConfig* c) {
  app.option_defaults()->always_capture_default();
  RegisterListenAndWorkerFlags(app, c);
  RegisterCallLimitFlags(app, c);
  RegisterStreamFlags(app, c);
  RegisterServiceFlags(app, c);
}

}  // namespace tactforce::server
