// Input validation with error messages that name the offending field using
// the API's field paths, e.g. "contacts[2].normal: zero length".
#pragma once

#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
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
inline constexpr double kMaxVelocity = 1e3;      // m/s
inline constexpr double kMaxAngularVelocity = 1e3;      // rad/s
inline constexpr double kMaxAngularAcceleration = 1e5;  // rad/s^2
inline constexpr double kMaxInertia = 1e12;             // kg m^2 (kMaxMass x kMaxLength^2)
inline constexpr double kMaxTime = 1e12;  // s: time stamps (epoch clocks, 1.7e9 s, fit)
// s: the smallest step between consecutive samples of a method that
// differentiates or fits over time (1 GHz: beyond any sensor); finer steps
// turn rounding into huge derivatives.
inline constexpr double kMinTimeStep = 1e-9;
// The shortest direction vector (normals, tangents) accepted.
inline constexpr double kMinDirectionLength = 1e-9;

// True when `value` (every component of it) is finite with magnitude at most
// `limit`. Cheap: callers format the field path only when this fails.
bool IsBounded(double value, double limit);
bool IsBounded(const Vec3& value, double limit);
// The error of a value IsBounded rejects: "<field>: not a finite number"
// ("... vector"), "<field>: magnitude exceeds <limit> <unit>" (vectors:
// "component magnitude exceeds ...").
absl::Status MagnitudeError(absl::string_view field, double value, double limit,
                            absl::string_view unit);
absl::Status MagnitudeError(absl::string_view field, const Vec3& value, double limit,
                            absl::string_view unit);
// IsBounded, else MagnitudeError.
absl::Status CheckMagnitude(absl::string_view field, double value, double limit,
                            absl::string_view unit);
absl::Status CheckMagnitude(absl::string_view field, const Vec3& value, double limit,
                            absl::string_view unit);
// A time stamp (s): finite and |t| <= kMaxTime; with `previous` (the
// sample before, already checked), also t - previous >= kMinTimeStep:
// "<field>: step 1e-302 s after the previous sample is below the resolution
// 1e-09 s". Order ("not increasing") is the caller's to name first.
absl::Status CheckTime(absl::string_view field, double t, const double* previous = nullptr);

// Scales `direction` to unit length without overflow (by its largest
// component first: |v| of a finite v may overflow). False, `direction`
// unchanged, when it is not finite or shorter than kMinDirectionLength.
bool NormalizeDirection(Vec3* direction);

// Checks every number (finite, in range) and returns a copy with unit
// normals; a normal of any finite non-zero length is normalised without
// overflow. Errors are
// absl::InvalidArgumentError("<field path>: <what is wrong>").
absl::StatusOr<PlanProblem> ValidateProblem(const PlanProblem& problem, const PlanOptions& options);
// The same into `validated` (which must not alias `problem`), reusing its
// storage; on error its contents are unspecified.
absl::Status ValidateProblem(const PlanProblem& problem, const PlanOptions& options,
                             PlanProblem* validated);

// A problem and the options it passed ValidateProblem with: normals of unit
// length, every number in range, the options valid. Only ValidatePlan fills
// one, so a solve that takes it (ForceSolver::Solve) checks nothing again:
// a front end that must refuse a bad request early (before queueing it)
// validates once and passes this down.
class ValidatedPlan {
 public:
  ValidatedPlan() = default;  // holds nothing validated: Solve refuses it
  const PlanProblem& problem() const { return problem_; }
  const PlanOptions& options() const { return options_; }
  bool validated() const { return validated_; }

 private:
  friend absl::Status ValidatePlan(const PlanProblem& problem, const PlanOptions& options,
                                   ValidatedPlan* plan);
  PlanProblem problem_;
  PlanOptions options_;
  bool validated_ = false;
};

// ValidateProblem's checks (same errors) into a ValidatedPlan; in place
// reusing `plan`'s storage (on error `plan` holds nothing validated).
absl::StatusOr<ValidatedPlan> ValidatePlan(const PlanProblem& problem, const PlanOptions& options);
absl::Status ValidatePlan(const PlanProblem& problem, const PlanOptions& options,
                          ValidatedPlan* plan);

// A rotational inertia about the CoM (kg m^2) that an object can have:
// finite, components at most kMaxInertia, positive semidefinite, principal moments obeying the
// triangle inequality (up to rounding). InvalidArgument("object.inertia: ...").
absl::Status ValidateInertia(const Inertia& inertia);

// One step of a motion (trajectory.h), "steps[i]...." in errors: gravity,
// accelerations and angular velocity finite and within the limits above;
// rotation needs `has_inertia` ("object.inertia: required because ...").
// The step's wrench and contacts are checked by ValidateProblem per step.
absl::Status ValidateTrajectoryStep(const TrajectoryStep& step, int index, bool has_inertia);

// A friction probe's numbers ("probe.normal: zero length", ...), with its
// unit normal and unit tangent (projected onto the tangent plane), each
// computed without overflow.
absl::Status ValidateFrictionProbe(const FrictionProbe& probe, Vec3* unit_normal,
                                   Vec3* unit_tangent);

}  // namespace tactforce::planner
