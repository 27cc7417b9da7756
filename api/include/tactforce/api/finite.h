// The last net under every answer: no OK response carries a NaN or an
// infinity. Inputs are bounded (planner/validation.h's limits), so a
// non-finite number in an answer is a computation that overflowed on valid
// input, a defect of ours: the call fails with INTERNAL naming the field
// instead of returning a silent wrong answer. (The planner already turns a
// non-finite solver answer into PLAN_STATUS_SOLVER_FAILURE inside the
// response; this covers every RPC the same way.)
#pragma once

#include <optional>
#include <string>
#include <utility>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "google/protobuf/message.h"
#include "tactforce/v1/planner.pb.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::api {

// The path of the first double or float field of `message` (depth first, in
// the .proto's declaration order) that is NaN or infinite, in the request paths' style:
// "holding.steps[3].forces[1].x", "causes[0].parameters[\"gain\"]",
// "causes[0].array_parameters[\"pi_weights\"].values[2]"; nullopt when all
// are finite. Fields whose documentation gives infinity a meaning (only
// FitInertiaResponse.pseudo_inertia_min_eigenvalue, -inf for a fit without
// positive mass, and InertiaErrors.riemannian, +inf for an inconsistent
// fit) may be infinite, never NaN. Allocates only when it finds one.
std::optional<std::string> FindNonFinite(const google::protobuf::Message& message);

// OK, or Internal("<path>: nan in the answer (...)").
absl::Status CheckFiniteAnswer(const google::protobuf::Message& response);
// The same for Plan's answer without reflection (Plan is the control-rate
// path, where the reflection walk would dominate this check); the same paths and
// message. tests/api/finite_test.cc checks it finds every double field the
// walk finds, so a field added to PlanResponse cannot slip past it.
absl::Status CheckFiniteAnswer(const v1::PlanResponse& response);

// `response` when it is an error or all finite; else CheckFiniteAnswer's error.
template <typename Response>
absl::StatusOr<Response> FiniteAnswer(absl::StatusOr<Response> response) {
  if (response.ok()) {
    TF_RETURN_IF_ERROR(CheckFiniteAnswer(*response));
  }
  return response;
}

}  // namespace tactforce::api
