// Request -> response paths of every RPC, shared by the CLI's local mode and
// the gRPC service (which runs them through dispatch.h): convert, call the
// library, convert back. !ok(): invalid request (InvalidArgument naming the
// field path; numbers past planner/validation.h's magnitude limits
// included), or Internal naming a response field that came out NaN or
// infinite (finite.h). ok(): a computed answer, every number finite;
// infeasibility and solver failures are statuses inside the response, not
// errors.
#pragma once

#include "absl/status/statusor.h"
#include "tactforce/api/call_limits.h"
#include "tactforce/api/convert.h"
#include "tactforce/planner/types.h"
#include "tactforce/planner/validation.h"
#include "tactforce/planner/workspace.h"
#include "tactforce/v1/audit.pb.h"
#include "tactforce/v1/estimator.pb.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// A PlanRequest converted (FromProto) with `limits` applied to its options
// (max_contacts; the Ipopt CPU cap, the tighter of the request's and
// solve_timeout_ms). Errors: InvalidArgument("<field path>: unknown value
// N"); the numeric checks are ValidatePlan's.
absl::StatusOr<PlanCall> PreparePlan(const v1::PlanRequest& request, const CallLimits& limits);
// The same into `call` (FromProto's in-place form: its storage reused).
absl::Status PreparePlan(const v1::PlanRequest& request, const CallLimits& limits, PlanCall* call);

// A PlanCall whose problem passed planner::ValidateProblem: made only by
// ValidatePlan, solved by SolvePlan without a second check.
struct ValidPlanCall {
  planner::ValidatedPlan plan;  // the problem and its options
  planner::SolverKind solver = planner::SolverKind::kGeometric;
};
// InvalidArgument naming the field ("contacts[2].normal: zero length").
absl::StatusOr<ValidPlanCall> ValidatePlan(const PlanCall& call);

// What a plan reuses from call to call: the converted request, the
// planner's workspace and result. One per thread (the default) or per
// stream (PlanStream: one solve at a time per stream).
struct PlanBuffers {
  PlanCall call;  // PreparePlan's, for a request solved where it was converted
  planner::PlanningWorkspace workspace;
  planner::PlanResult result;
};
// The calling thread's PlanBuffers.
PlanBuffers& ThreadPlanBuffers();
// Plans a request with `buffers` (the calling thread's when null) and
// converts the answer; `state.interrupt` is polled by Ipopt. The PlanCall
// form validates into the buffers (a warm GEOMETRIC solve allocates only
// the response), the ValidPlanCall form checks nothing again.
absl::StatusOr<v1::PlanResponse> SolvePlan(const PlanCall& call, const CallState& state = {},
                                           PlanBuffers* buffers = nullptr);
absl::StatusOr<v1::PlanResponse> SolvePlan(const ValidPlanCall& call, const CallState& state = {},
                                           PlanBuffers* buffers = nullptr);
// The same into `response` (the caller's, e.g. on a gRPC call's arena:
// filled in place, no copy); on an error its content is unspecified.
absl::Status SolvePlan(const PlanCall& call, const CallState& state, PlanBuffers* buffers,
                       v1::PlanResponse* response);
absl::Status SolvePlan(const ValidPlanCall& call, const CallState& state, PlanBuffers* buffers,
                       v1::PlanResponse* response);

// PreparePlan + SolvePlan.
absl::StatusOr<v1::PlanResponse> HandlePlan(const v1::PlanRequest& request,
                                            const CallLimits& limits = {},
                                            const CallState& state = {});
absl::StatusOr<v1::TrajectoryResponse> HandleTrajectory(const v1::TrajectoryRequest& request,
                                                        const CallLimits& limits = {},
                                                        const CallState& state = {});
absl::StatusOr<v1::FrictionProbeResponse> HandleFrictionProbe(
    const v1::FrictionProbeRequest& request, const CallLimits& limits = {},
    const CallState& state = {});
absl::StatusOr<v1::EstimateResponse> HandleEstimate(const v1::EstimateRequest& request,
                                                    const CallLimits& limits = {},
                                                    const CallState& state = {});
absl::StatusOr<v1::FrictionResponse> HandleFriction(const v1::FrictionRequest& request,
                                                    const CallLimits& limits = {},
                                                    const CallState& state = {});
absl::StatusOr<v1::AuditResponse> HandleAudit(const v1::AuditRequest& request,
                                              const CallLimits& limits = {},
                                              const CallState& state = {});

}  // namespace tactforce::api
