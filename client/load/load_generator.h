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
#include "load_spec.h"

namespace tactforce::cli {

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
