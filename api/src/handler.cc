#include "tactforce/api/handler.h"

#include "tactforce/api/services.h"

namespace tactforce::api {

absl::StatusOr<v1::PlanResponse> HandlePlan(const v1::PlanRequest& request) {
  // Solve() validates (InvalidArgument naming the field) before planning.
  return HandlePlan(request, CallLimits{});
}

}  // namespace tactforce::api
