// Input validation with error messages that name the offending field using
// the API's field paths, e.g. "contacts[2].normal: zero length".
#pragma once

#include "absl/status/statusor.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner {

// Checks every number and returns a copy with unit normals. Errors are
// absl::InvalidArgumentError("<field path>: <what is wrong>").
absl::StatusOr<PlanProblem> ValidateProblem(const PlanProblem& problem,
                                            const PlanOptions& options);
// The same into `validated` (which must not alias `problem`), reusing its
// storage; on error its contents are unspecified.
absl::Status ValidateProblem(const PlanProblem& problem, const PlanOptions& options,
                             PlanProblem* validated);

}  // namespace tactforce::planner
