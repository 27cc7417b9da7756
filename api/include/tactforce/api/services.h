// Request -> response paths of every RPC, shared by the CLI's local mode and
// the gRPC service (which runs them through dispatch.h): convert, call the
// library, convert back. !ok(): invalid request (InvalidArgument naming the
// field path; numbers past planner/validation.h's magnitude limits
// included), or Internal naming a response field that came out NaN or
// infinite (finite.h). ok(): a computed answer, every number finite;
// infeasibility and solver failures are statuses inside the response, not
// errors.
#pragma once

#include <cstdint>
#include <functional>

#include "absl/status/statusor.h"
#include "tactforce/api/convert.h"
#include "tactforce/planner/types.h"
#include "tactforce/planner/workspace.h"
#include "tactforce/v1/audit.pb.h"
#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// Limits a service imposes on every call (the CLI uses the defaults).
struct CallLimits {
  int max_contacts = planner::PlanOptions{}.max_contacts;
  double ipopt_max_cpu_seconds = 0.0;  // 0 = none
  std::function<bool()> interrupt;     // deadline / cancellation
  // PlanTrajectory / PlanFrictionProbe: at most this many steps x contacts x
  // cone sides, checked before any solve (the server's --max-trajectory-work).
  int64_t max_trajectory_work = 4'000'000;
  // Largest response the caller can send (bytes; 0 = no limit): a
  // trajectory, probe or audit whose answer cannot fit is refused before
  // any work (InvalidArgument naming the limit).
  int64_t max_response_bytes = 0;
  // Time one call's work may take, in seconds (0 = none): wall clock on
  // the thread doing it, from when the work starts (queue wait excluded);
  // the server's --solve-timeout-ms. Long loops poll `interrupt`, which the
  // dispatcher extends with this budget (WorkBudget, dispatch.h); a call
  // that runs out stops with RESOURCE_EXHAUSTED naming the flag.
  double max_call_seconds = 0.0;
  // AuditModel: most samples one request may carry (the server's
  // --max-audit-samples).
  int64_t max_audit_samples = 1'000'000;
  // FitInertia: most working memory one fit may take (bytes, estimated
  // before it starts with inertia::FitWorkingBytes; 0 = no limit; the
  // server's --max-fit-bytes).
  int64_t max_fit_bytes = 0;
};

// A PlanRequest converted (FromProto) with `limits` applied to its options.
// Errors: InvalidArgument("<field path>: unknown value N"); the numeric
// checks are planner::ValidateProblem's, which every solve runs.
absl::StatusOr<PlanCall> PreparePlan(const v1::PlanRequest& request, const CallLimits& limits);
// Plans a prepared request (validation included) and converts the answer.
absl::StatusOr<v1::PlanResponse> SolvePlan(const PlanCall& call);

// What a plan reuses from call to call: the planner's workspace and result.
// One per thread (the default) or per stream (PlanStream: one solve at a
// time per stream).
struct PlanBuffers {
  planner::PlanningWorkspace workspace;
  planner::PlanResult result;
};
// The calling thread's PlanBuffers.
PlanBuffers& ThreadPlanBuffers();
// SolvePlan with `buffers` (a warm GEOMETRIC solve allocates only the
// response).
absl::StatusOr<v1::PlanResponse> SolvePlan(const PlanCall& call, PlanBuffers* buffers);
// The same into `response` (the caller's, e.g. on a gRPC call's arena:
// filled in place, no copy); on an error its content is unspecified.
absl::Status SolvePlan(const PlanCall& call, PlanBuffers* buffers, v1::PlanResponse* response);

// PreparePlan + SolvePlan.
absl::StatusOr<v1::PlanResponse> HandlePlan(const v1::PlanRequest& request,
                                            const CallLimits& limits = {});
absl::StatusOr<v1::TrajectoryResponse> HandleTrajectory(const v1::TrajectoryRequest& request,
                                                        const CallLimits& limits = {});
absl::StatusOr<v1::FrictionProbeResponse> HandleFrictionProbe(
    const v1::FrictionProbeRequest& request, const CallLimits& limits = {});
absl::StatusOr<v1::EstimateResponse> HandleEstimate(const v1::EstimateRequest& request,
                                                    const CallLimits& limits = {});
absl::StatusOr<v1::FrictionResponse> HandleFriction(const v1::FrictionRequest& request,
                                                    const CallLimits& limits = {});
absl::StatusOr<v1::AuditResponse> HandleAudit(const v1::AuditRequest& request,
                                              const CallLimits& limits = {});

}  // namespace tactforce::api
