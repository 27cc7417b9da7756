// Conversions between the wire API (tactforce.v1 messages) and the planner
// types.
//
// Only the mapping is done here: enum defaults (UNSPECIFIED -> INTRINSIC /
// PYRAMID / GEOMETRIC), cone_sides 0, confidence absent and gravity absent
// -> the planner's defaults (planner::PlanOptions{}: 12 sides, kappa 1.0;
// ObjectModel{}: (0, 0, -9.81)), and unknown numeric enum values are
// rejected naming the field ("contacts[1].kind: unknown value 7"). Numeric
// range checks (NaN, zero normals, negative friction, ...) are the planner's
// ValidateProblem, which every Solve() runs with the same field paths.
#pragma once

#include <string>

#include "absl/status/statusor.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/planner/types.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// Everything needed for one planner call.
struct PlanCall {
  planner::PlanProblem problem;
  planner::PlanOptions options;
  planner::SolverKind solver = planner::SolverKind::kGeometric;
};

// One contact; `path` prefixes error fields ("contacts[2]").
absl::StatusOr<planner::Contact> ContactFromProto(const v1::Contact& contact,
                                                  const std::string& path);

// Errors: InvalidArgument("<field path>: unknown value N").
absl::StatusOr<PlanCall> FromProto(const v1::PlanRequest& request);
// The same into `call`, every field overwritten; its contact list and the
// contacts' name strings are reused, so converting into a PlanCall kept
// from call to call allocates nothing once it has held as many contacts.
// On an error `call` is unspecified.
absl::Status FromProto(const v1::PlanRequest& request, PlanCall* call);
absl::StatusOr<planner::PlanProblem> ToProblem(const v1::PlanRequest& request);
absl::StatusOr<planner::PlanOptions> ToOptions(const v1::PlanRequest& request);
absl::StatusOr<planner::SolverKind> ToSolverKind(const v1::PlanRequest& request);
// The given fields of `in` over `options`, then PlanOptions::IsValid:
// InvalidArgument("solver_options.ipopt_tolerance: must be finite and > 0").
absl::Status ApplySolverOptions(const v1::SolverOptions& in, planner::PlanOptions* options);

// The motion of a TrajectoryRequest over `base` (FromProto(request.plan())'s
// problem): inertia, and per step gravity (absent: base's), accelerations,
// velocities, replacement contacts ("steps[3].contacts[1]..." in errors) and
// the extra external wrench.
absl::StatusOr<planner::TrajectoryProblem> ToTrajectoryProblem(const v1::TrajectoryRequest& request,
                                                               const planner::PlanProblem& base);

// Planner -> wire. Every field is written explicitly (UNSPECIFIED enums are
// never produced), so a request round-trips through FromProto unchanged.
v1::PlanRequest ToRequest(const planner::PlanProblem& problem, const planner::PlanOptions& options,
                          planner::SolverKind solver);
v1::PlanResponse ToProto(const planner::PlanResult& result);
// The same into `out` (cleared first; on its arena, without a copy).
void ToProto(const planner::PlanResult& result, v1::PlanResponse* out);

// ObjectModel.uncertainty of an object of `mass` and `com`: the 10x10
// covariance (100 entries, checked by the planner's validation) or the
// short form mass_sigma / com_covariance converted to it; errors name the
// field ("object.uncertainty.covariance: 99 entries, need 100 ...").
absl::Status UncertaintyFromProto(const v1::ParameterUncertainty& in, double mass,
                                  const planner::Vec3& com, planner::ParameterUncertainty* out);

// Single-value mappings.
v1::Vec3 ToProto(const planner::Vec3& v);
planner::Vec3 FromProto(const v1::Vec3& v);
v1::PlanStatus ToProto(planner::PlanStatus status);
v1::Solver ToProto(planner::SolverKind solver);
v1::ContactKind ToProto(planner::ContactKind kind);
v1::ConeModel ToProto(planner::ConeModel cone);

}  // namespace tactforce::api
