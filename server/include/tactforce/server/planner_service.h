// tactforce.v1.Planner over the gRPC callback API: a thin adapter
//   api::FromProto -> server-level options -> planner::Plan -> api::ToProto.
// No planning logic lives here.
//
// Threads. The callback API runs Plan() / the stream reactions on gRPC's
// own threads, which must not be blocked by CPU-heavy work. A request runs
// in one of two places:
//   * inline, on the gRPC thread: SOLVER_GEOMETRIC with at most
//     `inline_max_contacts` contacts (default 8). Solver time, measured on
//     the 2-core dev box (Release): sphere-pinch 6.5 us, wrench-3f 61 us,
//     8 random contacts p50 160 us / p90 230 us, i.e. no worse than the
//     gRPC work around it. A pool hand-off costs more than it saves: one
//     client, 2,000 sequential Plans, 3 alternating runs each,
//       wrench-3f   p50 104-123 us inline vs 129-141 us pooled
//       8 contacts  p50 181-210 us inline vs 213-297 us pooled
//     and with 8 clients x 2,000 plans throughput was the same within the
//     noise of the shared box (median 5,400 vs 5,100 plans/s).
//   * on the WorkerPool: SOLVER_IPOPT and SOLVER_CROSS_CHECK (~20-200 ms)
//     and larger geometric problems (cost grows ~n^3: 16 contacts p50 2 ms,
//     64 contacts ~66 ms). The pool has a fixed number of threads and a
//     bounded queue; when it is full the RPC fails with RESOURCE_EXHAUSTED
//     instead of queueing more. Note that the Ipopt backend serialises its
//     runs process-wide (Debian's sequential MUMPS is not thread-safe), so
//     Ipopt throughput is one solve at a time per server process whatever
//     --workers is; scale Ipopt-heavy load with replicas.
// Requests bound for the pool are validated first (planner::ValidateProblem,
// a few microseconds), so a bad request is INVALID_ARGUMENT even under
// overload and never takes a queue slot.
//
// Deadlines and cancellation. PlanOptions::interrupt polls the RPC's
// deadline and cancellation (Ipopt checks it between iterations); a queued
// solve checks both before it starts; a call whose deadline passed returns
// DEADLINE_EXCEEDED, a cancelled one CANCELLED.
//
// PlanStream answers each request in order with one response: it reads a
// request, solves it (inline or on the pool), writes the response, then
// reads the next, so at most one solve per stream is in flight and order is
// preserved by construction. The first invalid request ends the stream with
// INVALID_ARGUMENT "request <i>: <field path>: ..." (i counts from 0).
#pragma once

#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "absl/status/statusor.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/services.h"
#include "tactforce/server/rpc_support.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/worker_pool.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::server {

struct PlannerServiceOptions {
  int max_contacts = 64;          // PlanOptions::max_contacts
  int solve_timeout_ms = 10'000;  // PlanOptions::ipopt_max_cpu_seconds; 0 = none
  int inline_max_contacts = 8;    // geometric solves this small run inline; 0 = never
};

class PlannerService final : public v1::Planner::CallbackService, public HostedService {
 public:
  // `pool` must outlive the service (and the gRPC server it is hosted on).
  PlannerService(WorkerPool* pool, PlannerServiceOptions options);

  std::string service_name() const override;
  grpc::Service* grpc_service() override { return this; }

  grpc::ServerUnaryReactor* Plan(grpc::CallbackServerContext* context,
                                 const v1::PlanRequest* request,
                                 v1::PlanResponse* response) override;
  grpc::ServerBidiReactor<v1::PlanRequest, v1::PlanResponse>* PlanStream(
      grpc::CallbackServerContext* context) override;
  // Whole motions and friction probes: always on the pool.
  grpc::ServerUnaryReactor* PlanTrajectory(grpc::CallbackServerContext* context,
                                           const v1::TrajectoryRequest* request,
                                           v1::TrajectoryResponse* response) override;
  grpc::ServerUnaryReactor* PlanFrictionProbe(grpc::CallbackServerContext* context,
                                              const v1::FrictionProbeRequest* request,
                                              v1::FrictionProbeResponse* response) override;

  // --- used by the reactors ---
  // Converts and applies the server-level options (INVALID_ARGUMENT on bad
  // enums; numeric checks happen in Validate / the solver).
  absl::StatusOr<api::PlanCall> Prepare(const v1::PlanRequest& request) const;
  bool RunsInline(const api::PlanCall& call) const;
  // Full validation, for requests about to be queued.
  absl::Status Validate(const api::PlanCall& call) const;
  // Solves `call`, honouring `guard`; fills `response` when OK.
  grpc::Status Execute(api::PlanCall& call, const RpcGuard& guard,
                       v1::PlanResponse* response) const;

  WorkerPool* pool() const { return pool_; }
  api::CallLimits Limits() const;
  const PlannerServiceOptions& options() const { return options_; }

 private:
  WorkerPool* pool_;
  PlannerServiceOptions options_;
};

}  // namespace tactforce::server
