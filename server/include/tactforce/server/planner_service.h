// tactforce.v1.Planner over the gRPC callback API: a thin adapter that
// hands each request to api:: dispatch (dispatch.h) with the RPC's
// RpcGuard, and finishes the gRPC call when api:: says it is done. No
// planning logic and no choice of thread lives here.
//
// Threads. The callback API runs Plan() / the stream reactions on gRPC's
// own threads, which must not be blocked by CPU-heavy work.
// api::PlanDispatcher runs small geometric plans (<= inline_max_contacts)
// inline and everything else (Ipopt, cross-checks, big problems) on the
// WorkerPool, validated before queueing; a full pool is RESOURCE_EXHAUSTED
// (dispatch.h has the measurements behind the split). PlanTrajectory and
// PlanFrictionProbe always run on the pool (ServeOnPool). The Ipopt backend
// serialises its runs process-wide (Debian's sequential MUMPS is not
// thread-safe), so Ipopt throughput is one solve at a time per server
// process whatever --workers is; scale Ipopt-heavy load with replicas.
//
// Deadlines and cancellation. PlanOptions::interrupt polls the RPC's
// deadline and cancellation (Ipopt checks it between iterations); a queued
// solve checks both before it starts; a call whose deadline passed returns
// DEADLINE_EXCEEDED, a cancelled one CANCELLED.
//
// PlanStream answers each request in order with one response: it reads a
// request, dispatches it (inline or on the pool), writes the response, then
// reads the next, so at most one solve per stream is in flight and order is
// preserved by construction. The first invalid request ends the stream with
// INVALID_ARGUMENT "request <i>: <field path>: ..." (i counts from 0).
// Streams are admitted and timed out by the StreamRegistry: beyond
// --max-streams a new one ends at once with RESOURCE_EXHAUSTED, and one that
// waits longer than --stream-idle-timeout-ms for its next request ends
// with UNAVAILABLE "request <i>: stream idle for more than ...".
#pragma once

#include <string>

#include <grpcpp/grpcpp.h>

#include "tactforce/api/dispatch.h"
#include "tactforce/api/services.h"
#include "tactforce/server/rpc_support.h"
#include "tactforce/server/server_host.h"
#include "tactforce/server/stream_registry.h"
#include "tactforce/server/worker_pool.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::server {

// PlanStream is registered raw (its reactor parses each message itself: see
// planner_service.cc); the unary RPCs are typed.
using PlannerBase = v1::Planner::WithCallbackMethod_Plan<
    v1::Planner::WithRawCallbackMethod_PlanStream<v1::Planner::WithCallbackMethod_PlanTrajectory<
        v1::Planner::WithCallbackMethod_PlanFrictionProbe<v1::Planner::Service>>>>;

class PlannerService final : public PlannerBase, public HostedService {
 public:
  // `pool`, `ipopt_lane` and `streams` must outlive the service (and the
  // gRPC server it is hosted on). `settings.limits` hold for every Planner
  // RPC. Work that runs Ipopt (SOLVER_IPOPT, SOLVER_CROSS_CHECK, in Plan,
  // PlanStream, PlanTrajectory and PlanFrictionProbe) goes to `ipopt_lane`,
  // everything else to `pool`.
  PlannerService(WorkerPool* pool, WorkerPool* ipopt_lane, StreamRegistry* streams,
                 api::PlanSettings settings);

  std::string service_name() const override;
  grpc::Service* grpc_service() override { return this; }

  grpc::ServerUnaryReactor* Plan(grpc::CallbackServerContext* context,
                                 const v1::PlanRequest* request,
                                 v1::PlanResponse* response) override;
  grpc::ServerBidiReactor<grpc::ByteBuffer, grpc::ByteBuffer>* PlanStream(
      grpc::CallbackServerContext* context) override;
  // Whole motions and friction probes: always on the pool.
  grpc::ServerUnaryReactor* PlanTrajectory(grpc::CallbackServerContext* context,
                                           const v1::TrajectoryRequest* request,
                                           v1::TrajectoryResponse* response) override;
  grpc::ServerUnaryReactor* PlanFrictionProbe(grpc::CallbackServerContext* context,
                                              const v1::FrictionProbeRequest* request,
                                              v1::FrictionProbeResponse* response) override;

 private:
  // The pool for a request of `solver`'s (the Ipopt lane or the main pool).
  WorkerPool* PoolFor(v1::Solver solver) const;

  WorkerPool* pool_;
  WorkerPool* ipopt_lane_;
  StreamRegistry* streams_;    // PlanStream's admission and idle timeout
  api::PlanDispatcher plans_;  // its settings' limits serve every Planner RPC
  // Plan's request and response on one arena per call.
  ArenaMessageAllocator<v1::PlanRequest, v1::PlanResponse> plan_messages_;
};

}  // namespace tactforce::server
