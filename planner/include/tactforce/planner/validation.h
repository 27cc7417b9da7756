// Input validation with error messages that name the offending field using
// the API's field paths, e.g. "contacts[2].normal: zero length".
#pragma once

#include "absl/status/statusor.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner {

// The largest magnitudes accepted. Far beyond any fingertip grasp, and small
// enough that no product the planner forms (forces are squared in the
// objective) can overflow: a finite but absurd input gets InvalidArgument
// naming its field instead of an infinite intermediate and a wrong status.
inline constexpr double kMaxLength = 1e3;        // m: contact positions, CoM
inline constexpr double kMaxMass = 1e6;          // kg
inline constexpr double kMaxAcceleration = 1e4;  // m/s^2: gravity
inline constexpr double kMaxForce = 1e9;         // N (N m for torques): wrench, force bounds, sigma
inline constexpr double kMaxFriction = 1e3;      // friction coefficient

// Checks every number (finite, in range) and returns a copy with unit
// normals; a normal of any finite non-zero length is normalised without
// overflow. Errors are
// absl::InvalidArgumentError("<field path>: <what is wrong>").
absl::StatusOr<PlanProblem> ValidateProblem(const PlanProblem& problem,
                                            const PlanOptions& options);
// The same into `validated` (which must not alias `problem`), reusing its
// storage; on error its contents are unspecified.
absl::Status ValidateProblem(const PlanProblem& problem, const PlanOptions& options,
                             PlanProblem* validated);

// A rotational inertia about the CoM (kg m^2) that an object can have:
// finite, positive semidefinite, principal moments obeying the triangle
// inequality (up to rounding). InvalidArgument("object.inertia: ...").
absl::Status ValidateInertia(const Inertia& inertia);

}  // namespace tactforce::planner
