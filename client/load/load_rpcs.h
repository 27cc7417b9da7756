// Inside the load generator: the one place that knows how each RPC of
// `tactforce load --rpc` is issued. Every call-per-request RPC is a traits
// struct with
//   Response             the response message
//   Start(...)           the call on gRPC's callback API; `done` runs once
//                        with the call's status (callback engines)
//   Call(...)            the same call, blocking (sync engine)
//   WarmUp(server, spec) one unmeasured call before the run, a failure as
//                        the CLI reports it (RemoteServer::Error)
// and VisitRpc picks the struct of a LoadRpc. PlanStream slots are a mode of
// their own (load_callback_engine.cc, load_sync_engine.cc) and warm up with
// Plan. FitInertia is client-streaming: one call writes spec's whole
// fit_inertia_stream and waits for the one response, so the engines drive
// it like a unary call. Only load_*.cc include this.
#pragma once

#include <grpcpp/grpcpp.h>

#include <cstdint>
#include <functional>
#include <vector>

#include "absl/status/status.h"
#include "load_spec.h"
#include "load_run.h"
#include "remote_call.h"

namespace tactforce::cli::load_engine {

// The request of call `ticket`: the requests are used round-robin.
template <class Request>
const Request& RoundRobin(const std::vector<Request>& requests, int64_t ticket) {
  return requests[static_cast<size_t>(ticket) % requests.size()];
}

using DoneCallback = std::function<void(grpc::Status)>;

struct PlanRpc {
  using Response = v1::PlanResponse;
  static void Start(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                    Response* response, DoneCallback done) {
    run.planners[channel]->async()->Plan(context, &run.PlanRequestFor(ticket), response,
                                         std::move(done));
  }
  static grpc::Status Call(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                           Response* response) {
    return run.planners[channel]->Plan(context, run.PlanRequestFor(ticket), response);
  }
  // Plan with the first request (also the warm-up of --rpc stream).
  static absl::Status WarmUp(const RemoteServer& server, const LoadSpec& spec);
};

struct HealthRpc {
  using Response = grpc::health::v1::HealthCheckResponse;
  static void Start(Run& run, int channel, grpc::ClientContext* context, int64_t /*ticket*/,
                    Response* response, DoneCallback done) {
    run.health[channel]->async()->Check(context, &run.health_request, response, std::move(done));
  }
  static grpc::Status Call(Run& run, int channel, grpc::ClientContext* context, int64_t /*ticket*/,
                           Response* response) {
    return run.health[channel]->Check(context, run.health_request, response);
  }
  // A service the server does not know is InvalidArgument naming --service.
  static absl::Status WarmUp(const RemoteServer& server, const LoadSpec& spec);
};

struct EstimateRpc {
  using Response = v1::EstimateResponse;
  static void Start(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                    Response* response, DoneCallback done) {
    run.estimators[channel]->async()->EstimateForces(
        context, &RoundRobin(run.spec.estimate_requests, ticket), response, std::move(done));
  }
  static grpc::Status Call(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                           Response* response) {
    return run.estimators[channel]->EstimateForces(
        context, RoundRobin(run.spec.estimate_requests, ticket), response);
  }
  static absl::Status WarmUp(const RemoteServer& server, const LoadSpec& spec);
};

struct AuditRpc {
  using Response = v1::AuditResponse;
  static void Start(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                    Response* response, DoneCallback done) {
    run.audits[channel]->async()->AuditModel(context, &RoundRobin(run.spec.audit_requests, ticket),
                                             response, std::move(done));
  }
  static grpc::Status Call(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                           Response* response) {
    return run.audits[channel]->AuditModel(context, RoundRobin(run.spec.audit_requests, ticket),
                                           response);
  }
  static absl::Status WarmUp(const RemoteServer& server, const LoadSpec& spec);
};

struct FitInertiaRpc {
  using Response = v1::FitInertiaResponse;
  // Writes the stream from a ClientWriteReactor (load_rpcs.cc).
  static void Start(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                    Response* response, DoneCallback done);
  static grpc::Status Call(Run& run, int channel, grpc::ClientContext* context, int64_t ticket,
                           Response* response);
  static absl::Status WarmUp(const RemoteServer& server, const LoadSpec& spec);
};

// fn(XxxRpc{}) for the struct of `rpc` (PlanRpc for kStream: the unary call
// of its kind, used to warm up).
template <class Fn>
decltype(auto) VisitRpc(LoadRpc rpc, Fn&& fn) {
  switch (rpc) {
    case LoadRpc::kHealth:
      return fn(HealthRpc{});
    case LoadRpc::kEstimate:
      return fn(EstimateRpc{});
    case LoadRpc::kFitInertia:
      return fn(FitInertiaRpc{});
    case LoadRpc::kAudit:
      return fn(AuditRpc{});
    case LoadRpc::kPlan:
    case LoadRpc::kStream:
      break;
  }
  return fn(PlanRpc{});
}

}  // namespace tactforce::cli::load_engine
