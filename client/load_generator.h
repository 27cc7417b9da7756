// The load generator behind `tactforce load` (and the demo's load test):
// drives tactforce-server with Plan, PlanStream or grpc.health.v1 Check
// calls and measures throughput and latency.
//
// Modes
//   closed loop (rate == 0): `concurrency` slots, each with one call in
//     flight; a slot starts its next call as soon as the previous one ends.
//     For the stream RPC each slot is one PlanStream that writes its next
//     request after each response.
//   open loop (rate > 0, unary RPCs only): calls are started on a fixed
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
#include "tactforce/v1/planner.pb.h"

namespace tactforce::cli {

enum class LoadRpc { kPlan, kStream, kHealth };
enum class LoadEngine { kCallback, kSync };

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
  std::vector<v1::PlanRequest> requests;  // plan/stream: used round-robin
  std::string health_service;             // health: the service asked about
  // Called from the driving thread about once a second (may be empty).
  std::function<void(const LoadProgress&)> progress;
  // Polled by the driving thread; true ends the run early (Ctrl-C).
  std::function<bool()> interrupted;
};

struct LoadReport {
  std::string rpc;     // "plan", "stream", "health"
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
  std::map<std::string, int64_t> errors;  // gRPC code name -> count
  bool interrupted = false;
};

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
// one unmeasured call per address of the kind `spec` makes (Plan with the
// first request for plan and stream), so an unreachable server or an invalid
// request is reported before the run (errors as RpcError, connection.h).
absl::StatusOr<std::vector<std::shared_ptr<grpc::Channel>>> ConnectLoadChannels(
    const ConnectionArgs& connection, const std::string& target_list, int per_target,
    const LoadSpec& spec);

// `count` seeded random grasps (planner::MakeRandomGrasp, 2-6 contacts,
// ~10 % infeasible on purpose) as SOLVER_GEOMETRIC requests.
std::vector<v1::PlanRequest> RandomRequestMix(uint64_t seed, int count);

// Human-readable summary (several lines, ends with a newline), and the
// one-line JSON object {rpc, concurrency, requests, duration_s, qps,
// latency_us: {p50, p90, p99, p999, max}, errors: {CODE: n}, ...}.
std::string FormatLoadText(const LoadReport& report, const std::string& target);
std::string FormatLoadJson(const LoadReport& report, const std::string& target);

}  // namespace tactforce::cli
