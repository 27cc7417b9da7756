// The load generator behind `tactforce load` (and the demo's load test):
// drives tactforce-server with Plan, PlanStream, grpc.health.v1 Check,
// EstimateForces, FitInertia or AuditModel calls and measures throughput,
// latency and completions over time.
//
// RPCs (load_rpcs.h issues each)
//   plan, health, estimate, audit: unary, one request per call.
//   fit-inertia: client-streaming; one call writes the whole request stream
//     (the same messages every time) and waits for the one response, and
//     its latency is the whole stream's. To the engines it is a unary call.
//   stream: PlanStream, one long stream per slot (below).
//
// Modes
//   closed loop (rate == 0): `concurrency` slots, each with one call in
//     flight; a slot starts its next call as soon as the previous one ends.
//     For the stream RPC each slot is one PlanStream that writes its next
//     request after each response.
//   open loop (rate > 0, every RPC but stream): calls are started on a fixed
//     schedule (rate per second) whatever the server does; at most
//     `concurrency` are in flight, a call that is due while that many are
//     outstanding waits, and latency is measured from the scheduled start
//     (no coordinated omission).
// Engines
//   callback: gRPC's callback API; all slots share gRPC's own threads.
//   sync: one thread per slot with blocking stubs (closed loop only).
// Bounds: `max_requests` calls started and/or `duration_s` seconds, whichever
// comes first; in-flight calls always finish (each has `deadline_ms`).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>

#include "absl/status/statusor.h"
#include "connection.h"
#include "latency_histogram.h"
#include "load_timeline.h"
#include "tactforce/v1/audit.pb.h"
#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/inertia.pb.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::cli {

enum class LoadRpc { kPlan, kStream, kHealth, kEstimate, kFitInertia, kAudit };
inline constexpr LoadRpc kAllLoadRpcs[] = {LoadRpc::kPlan,     LoadRpc::kStream,
                                           LoadRpc::kHealth,   LoadRpc::kEstimate,
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
  std::vector<v1::PlanRequest> requests;  // plan/stream: used round-robin
  std::string health_service;             // health: the service asked about
  std::vector<v1::EstimateRequest> estimate_requests;  // estimate: round-robin
  std::vector<v1::AuditRequest> audit_requests;        // audit: round-robin
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

// Runs the load on `channels` (slot i / call i uses channel i % size),
// normally made and warmed up by ConnectLoadChannels. Errors
// (InvalidArgument) only for an unusable spec; failed calls are counted in
// the report.
absl::StatusOr<LoadReport> RunLoad(const LoadSpec& spec,
                                   const std::vector<std::shared_ptr<grpc::Channel>>& channels);

// The channels for a load run on `target_list` (see SplitTargets): for each
// entry `per_target` channels, each with its own connection; a gRPC URI
// entry (ipv4:127.0.0.1:50051,127.0.0.1:50052) gets gRPC's round_robin
// policy over its addresses. Each channel is connected and warmed up with
// one unmeasured call per address of the kind `spec` makes (its first
// request; Plan for stream; the whole stream for fit-inertia; with a
// deadline of at least 10 s whatever connection.deadline_ms), so an
// unreachable server or an invalid request is reported before the run
// (errors as RpcError, connection.h).
absl::StatusOr<std::vector<std::shared_ptr<grpc::Channel>>> ConnectLoadChannels(
    const ConnectionArgs& connection, const std::string& target_list, int per_target,
    const LoadSpec& spec);

// `count` seeded random grasps (planner::MakeRandomGrasp, 2-6 contacts,
// ~10 % infeasible on purpose) as SOLVER_GEOMETRIC requests.
std::vector<v1::PlanRequest> RandomRequestMix(uint64_t seed, int count);

// Human-readable summary (several lines, ends with a newline), and the
// one-line JSON object {rpc, concurrency, requests, duration_s, qps,
// latency_us: {p50, p90, p99, p999, max} (successful calls),
// latency_all_us: {p50, p90, p99, max} (every call, failed ones included),
// errors: {CODE: n}, ...}.
std::string FormatLoadText(const LoadReport& report, const std::string& target);
std::string FormatLoadJson(const LoadReport& report, const std::string& target);

}  // namespace tactforce::cli
