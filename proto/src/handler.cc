#include "tactforce/api/handler.h"

#include "tactforce/api/convert.h"
#include "tactforce/planner/solver.h"

namespace tactforce::api {

absl::StatusOr<v1::PlanResponse> HandlePlan(const v1::PlanRequest& request) {
  absl::StatusOr<PlanCall> call = FromProto(request);
  if (!call.ok()) return call.status();
  // Solve() validates (InvalidArgument naming the field) before planning.
  absl::StatusOr<planner::PlanResult> result =
      planner::Plan(call->problem, call->options, call->solver);
  if (!result.ok()) return result.status();
  return ToProto(*result);
}

}  // namespace tactforce::api
