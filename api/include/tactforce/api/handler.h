// The one request -> response path shared by every front end (the CLI's
// local mode now, the gRPC service later): convert, plan, convert back.
#pragma once

#include "absl/status/statusor.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// !ok(): the request is invalid (InvalidArgument naming the field path).
// ok(): a computed answer; infeasibility and solver failures are statuses in
// the response, not errors.
absl::StatusOr<v1::PlanResponse> HandlePlan(const v1::PlanRequest& request);

}  // namespace tactforce::api
