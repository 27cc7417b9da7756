// tactforce-server: the gRPC front end of the tactforce planner.
// See server/README.md; every flag is documented by --help.
#include <pthread.h>
#include <signal.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <thread>

#include <grpc/support/log.h>

#include "CLI/CLI.hpp"
#include "absl/synchronization/mutex.h"
#include "spdlog/sinks/stdout_sinks.h"
#include "spdlog/spdlog.h"
#include "tactforce/api/version.h"
#include "tactforce/server/estimator_service.h"
#include "tactforce/server/info_service.h"
#include "tactforce/server/planner_service.h"
#include "tactforce/server/rpc_support.h"
#include "tactforce/server/server_config.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/stream_registry.h"
#include "tactforce/server/worker_pool.h"

namespace {

using tactforce::server::ServerConfig;

spdlog::level::level_enum ParseLevel(const std::string& name) {
  if (name == "off") return spdlog::level::off;
  if (name == "error") return spdlog::level::err;
  if (name == "info") return spdlog::level::info;
  if (name == "debug") return spdlog::level::debug;
  return spdlog::level::warn;
}

// gRPC's own log lines (failed TLS handshakes, ...) through the same logger,
// so --log-level governs them too (off: nothing on stderr). gRPC keeps its
// verbosity (GRPC_VERBOSITY, default ERROR).
void LogGrpcLine(gpr_log_func_args* args) {
  const spdlog::level::level_enum level =
      args->severity == GPR_LOG_SEVERITY_ERROR  ? spdlog::level::err
      : args->severity == GPR_LOG_SEVERITY_INFO ? spdlog::level::info
                                                : spdlog::level::debug;
  if (spdlog::should_log(level)) {
    spdlog::log(level, "source=grpc file={}:{} message={}", args->file, args->line,
                tactforce::server::LogValue(args->message != nullptr ? args->message : ""));
  }
}

// After main's loggers are gone, gRPC's exit-time lines are dropped.
void DropGrpcLine(gpr_log_func_args*) {}

void SetUpLogging(const std::string& level) {
  // stdout carries only the "listening on" line; logs go to stderr.
  auto logger = spdlog::stderr_logger_mt("tactforce-server");
  spdlog::set_default_logger(logger);
  spdlog::set_pattern("ts=%Y-%m-%dT%H:%M:%S.%fZ level=%l %v", spdlog::pattern_time_type::utc);
  spdlog::set_level(ParseLevel(level));
  spdlog::flush_on(spdlog::level::trace);
  gpr_set_log_function(&LogGrpcLine);
}

bool AllInterfaces(const std::string& address) {
  return address.rfind("0.0.0.0:", 0) == 0 || address.rfind("[::]:", 0) == 0 ||
         address.rfind(":", 0) == 0;
}

// One line with every limit in force.
void LogStart(const ServerConfig& c, const tactforce::server::ServerHost& host,
              const tactforce::server::WorkerPool& pool) {
  spdlog::info(
      "event=start address={} tls={} mtls={} reflection={} workers={} ipopt_workers={} queue={} "
      "max_contacts={} solve_timeout_ms={} inline_max_contacts={} max_message_bytes={} "
      "max_inertia_samples={} max_inflight_samples={} max_inflight_bytes={} max_fit_bytes={} "
      "max_audit_samples={} "
      "max_streams={} stream_idle_timeout_ms={} max_streams_per_connection={} "
      "max_trajectory_work={}",
      host.bound_address(), host.tls(), !c.tls_client_ca.empty(), c.reflection, pool.workers(),
      c.ipopt_workers, pool.max_queued(), c.limits.max_contacts, c.solve_timeout_ms(),
      c.inline_max_contacts, c.limits.max_response_bytes, c.max_inertia_samples,
      c.max_inflight_samples, c.max_inflight_bytes, c.limits.max_fit_bytes,
      c.limits.max_audit_samples, c.max_streams, c.stream_idle_timeout_ms,
      c.max_streams_per_connection, c.limits.max_trajectory_work);
}

}  // namespace

int main(int argc, char** argv) {
  ServerConfig config;
  CLI::App app{
      "tactforce-server: gRPC services tactforce.v1.Planner, Estimator, Audit and Info with "
      "the standard health service and server reflection.\n"
      "SIGINT/SIGTERM drain in-flight calls (--grace-ms) and exit 0; a second signal "
      "exits at once.",
      "tactforce-server"};
  app.set_version_flag("--version", std::string("tactforce-server ") + tactforce::api::kVersion);
  tactforce::server::RegisterFlags(app, &config);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every flag error exits 2 (as the CLI does)
    // with CLI11's message naming the flag.
    return app.exit(e) == 0 ? 0 : 2;
  }

  // Debian's Abseil is built with Mutex deadlock detection on (no NDEBUG),
  // and gRPC's locks are absl::Mutex: every lock would update a global
  // lock-order graph (GraphCycles), measurable under load. Off before any
  // thread starts.
  absl::SetMutexDeadlockDetectionMode(absl::OnDeadlockCycle::kIgnore);

  // Block the shutdown signals before any thread exists, so every thread
  // (gRPC's included) inherits the mask and only sigwait() below sees them.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);
  std::signal(SIGPIPE, SIG_IGN);

  SetUpLogging(config.log_level);

  tactforce::server::WorkerPool pool(config.EffectiveWorkers(), config.queue);
  tactforce::server::WorkerPool ipopt_lane(config.ipopt_workers, config.queue);
  tactforce::server::StreamRegistry streams(config.ToStreamLimits());
  tactforce::server::ServerHost host(config.ToServerOptions());
  host.AddService(std::make_unique<tactforce::server::PlannerService>(&pool, &ipopt_lane, &streams,
                                                                      config.ToPlanSettings()));
  host.AddService(std::make_unique<tactforce::server::EstimatorService>(
      &pool, &streams, config.limits, config.max_inertia_samples));
  host.AddService(std::make_unique<tactforce::server::AuditService>(&pool, config.limits));
  host.AddService(std::make_unique<tactforce::server::InfoService>(&host));

  if (absl::Status started = host.Start(); !started.ok()) {
    std::fprintf(stderr, "tactforce-server: %s\n", std::string(started.message()).c_str());
    return 1;
  }
  std::printf("tactforce-server listening on %s\n", host.bound_address().c_str());
  std::fflush(stdout);
  LogStart(config, host, pool);
  if (AllInterfaces(config.listen) && !host.tls()) {
    spdlog::warn(
        "event=plaintext_all_interfaces address={} note=\"listening on every "
        "interface without TLS\"",
        host.bound_address());
  }

  int signal_number = 0;
  sigwait(&stop_signals, &signal_number);
  spdlog::info("event=shutdown signal={} grace_ms={}", strsignal(signal_number), config.grace_ms);
  // A second SIGINT/SIGTERM while draining: give up at once.
  std::thread([stop_signals]() {
    int again = 0;
    sigwait(&stop_signals, &again);
    std::fprintf(stderr, "tactforce-server: second signal, exiting without draining\n");
    std::_Exit(128 + again);
  }).detach();

  host.Shutdown(std::chrono::milliseconds(config.grace_ms));
  pool.Shutdown();
  ipopt_lane.Shutdown();
  spdlog::info("event=stopped");
  gpr_set_log_function(&DropGrpcLine);
  return 0;
}
