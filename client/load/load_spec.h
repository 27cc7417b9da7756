// What a load run is and what it measured: the RPC, the engine, the
// bounds and requests of a run (LoadSpec) and its report (LoadReport).
// Shared by the generator (load_generator.h), the per-RPC calls
// (load_rpcs.h), the run state (load_run.h), requests and plot; it
// includes none of them, so the load library has no include cycle.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <vector>

#include "latency_histogram.h"
#include "load_timeline.h"
#include "tactforce/v1/audit.pb.h"
#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/inertia.pb.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::cli {

enum class LoadRpc { kPlan, kStream, kHealth, kEstimate, kFitInertia, kAudit };
inline constexpr LoadRpc kAllLoadRpcs[] = {LoadRpc::kPlan,       LoadRpc::kStream,
                                           LoadRpc::kHealth,     LoadRpc::kEstimate,
                                           LoadRpc::kFitInertia, LoadRpc::kAudit};
enum class LoadEngine { kCallback, kSync };

// "plan", "stream", "health", "estimate", "fit-inertia", "audit" (the
// --rpc spellings).
const char* ToString(LoadRpc rpc);
const char* ToString(LoadEngine engine);

// Snapshot for progress lines.
struct LoadProgress {
  double elapsed_s = 0;
  int64_t completed = 0;  // calls finished, ok or not
  int64_t failed = 0;
  double recent_qps = 0;  // completed calls per second since the last snapshot
};

struct LoadSpec {
  LoadRpc rpc = LoadRpc::kPlan;
  LoadEngine engine = LoadEngine::kCallback;
  int concurrency = 1;       // closed loop: calls in flight; open loop: the cap
  double rate = 0;           // calls per second; 0 = closed loop
  int64_t max_requests = 0;  // 0 = no count bound
  double duration_s = 0;     // 0 = no time bound (then max_requests must be > 0)
  int deadline_ms = 10'000;  // per call, per response on streams; 0 = none
  // What the calls send; each RPC needs its own (RunLoad checks).
  std::vector<v1::PlanRequest> requests;                  // plan/stream: used round-robin
  std::string health_service;                             // health: the service asked about
  std::vector<v1::EstimateRequest> estimate_requests;     // estimate: round-robin
  std::vector<v1::AuditRequest> audit_requests;           // audit: round-robin
  std::vector<v1::FitInertiaRequest> fit_inertia_stream;  // fit-inertia: each call's stream
  // Called from the driving thread about once a second (may be empty).
  std::function<void(const LoadProgress&)> progress;
  // Polled by the driving thread; true ends the run early (Ctrl-C).
  std::function<bool()> interrupted;
};

struct LoadReport {
  std::string rpc;     // ToString(LoadRpc)
  std::string mode;    // "closed" or "open"
  std::string engine;  // "callback" or "sync"
  int concurrency = 0;
  double rate = 0;
  int channels = 0;
  int64_t requests = 0;  // calls finished (ok + failed)
  int64_t ok = 0;
  double duration_s = 0;  // first call started -> last call finished
  double qps = 0;         // successful calls per second
  // Successful calls only, microseconds.
  double p50_us = 0, p90_us = 0, p99_us = 0, p999_us = 0, max_us = 0;
  // Every call whatever its status (time to completion, a DEADLINE_EXCEEDED
  // or RESOURCE_EXHAUSTED call included), microseconds.
  double all_p50_us = 0, all_p90_us = 0, all_p99_us = 0, all_max_us = 0;
  std::map<std::string, int64_t> errors;  // gRPC code name -> count
  bool interrupted = false;
  // For plots: successful calls' latencies in log-spaced bins
  // (kLatencyBinsPerDecade per factor 10), and the calls that ended in each
  // interval from the first call's start to the last one's end.
  std::vector<LatencyHistogram::Bin> latency_bins;
  CompletionCounts timeline;
};

inline constexpr int kLatencyBinsPerDecade = 20;

}  // namespace tactforce::cli
