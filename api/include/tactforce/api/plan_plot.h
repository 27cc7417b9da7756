// Pictures of a plan for people (`tactforce plan --plot FILE`), drawn with
// io/svg.h: three orthographic views of the object frame (x-y, x-z, y-z)
// side by side, each with the contacts (points and inward normals), their
// robust friction cones, the planned forces as arrows, the 1-sigma spread of
// each force under the trusted measurement ellipsoid (the projected 3x3
// block S_ii, centred on the force's tip), the centre of mass and the
// gravity direction; a legend states the units and the force scale.
//
// The geometry is the request's (PreparePlan + planner::Prepare, so the same
// tightening the planner used); only the forces come from the response, so
// a remote plan is drawn exactly like a local one.
//
// The robust cone as drawn (one honest depiction, stated in the legend):
//  * EXACT: the circular cone of half-angle atan(mu) with its apex moved
//    along the normal by cone_shift / mu: exactly the tightened cone
//    |P f| <= mu n.f - cone_shift.
//  * PYRAMID: the k-facet pyramid (edges on the circular cone, facet normals
//    at 2 pi j / k about TangentBasis) with its apex moved along the normal by
//    max_j (nominal_rhs_j - rhs_j) / (mu cos(pi / k)): the largest facet
//    tightening. Every point of the drawn pyramid satisfies every tightened
//    facet row; it is the tightened region exactly when the facets are
//    tightened equally.
//
// Elements carry classes for readers and tests: each view is
// <g class="view" id="view-xy|view-xz|view-yz">; per contact and view one
// <g class="cone|force-arrow|spread-ellipse|contact-point|normal"
// data-contact="i">; per view one <g class="com"> and one <g class="gravity">;
// the legend is <g id="legend">; a trajectory step is
// <g class="step-panel" data-step="k">.
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include <Eigen/Core>

#include "absl/status/statusor.h"
#include "tactforce/planner/types.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// The most steps a trajectory plot draws; longer trajectories are
// subsampled evenly (first and last step included) and the figure says which.
inline constexpr int kMaxPlotSteps = 24;

// What is drawn of one contact (object frame, SI units).
struct ContactGlyph {
  std::string label;                               // the contact's name, else "contact i"
  planner::Vec3 position = planner::Vec3::Zero();  // m
  planner::Vec3 normal = planner::Vec3::UnitZ();   // unit, into the object
  planner::Vec3 tangent1 = planner::Vec3::UnitX(),
                tangent2 = planner::Vec3::UnitY();  // TangentBasis
  double friction = 0;
  int cone_sides = 0;      // facets of the drawn pyramid; 0: the exact circular cone
  double apex_shift = 0;   // N along the normal: the drawn robust cone's apex
  bool has_force = false;  // the response carries a force for this contact
  planner::Vec3 force = planner::Vec3::Zero();           // N
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();  // S_ii of the trusted ellipsoid (N^2)
  // (G^+ S_b G^+T)_ii: the force spread the inertial-parameter uncertainty
  // causes (N^2); zero without object.uncertainty.
  Eigen::Matrix3d parameter_covariance = Eigen::Matrix3d::Zero();
};

// One plan as drawn.
struct PlanScene {
  std::string status;    // "OPTIMAL", "INFEASIBLE", ...
  std::string settings;  // "2 contacts, 12-facet pyramids, confidence 1, solver GEOMETRIC"
  std::string outcome;   // "objective 1.2 N², min margin 0.3 N" and the message, if any
  planner::Vec3 com = planner::Vec3::Zero();
  planner::Vec3 gravity = planner::Vec3::Zero();  // m/s^2
  std::vector<ContactGlyph> contacts;
};

// The scene of `response` planned for `problem` with `options` (validated and
// prepared here). Errors: the planner's validation (field paths).
absl::StatusOr<PlanScene> BuildPlanScene(const planner::PlanProblem& problem,
                                         const planner::PlanOptions& options,
                                         const v1::PlanResponse& response);

// The SVG document of one plan; `source` (the request's file name; may be
// empty) is named under the title. Errors: the request's (field paths).
absl::StatusOr<std::string> PlanSvg(const v1::PlanRequest& request,
                                    const v1::PlanResponse& response, std::string_view source = "");

// Which of `steps` steps a trajectory plot shows: all when at most
// `max_steps`, else `max_steps` evenly spaced ones from the first to the last.
std::vector<int> PlottedSteps(int steps, int max_steps = kMaxPlotSteps);

// Small multiples of a trajectory: one panel per plotted step (the three
// views, small), all at one length and force scale, and one legend; `source`
// as in PlanSvg.
absl::StatusOr<std::string> TrajectorySvg(const v1::TrajectoryRequest& request,
                                          const v1::TrajectoryResponse& response,
                                          std::string_view source = "");

}  // namespace tactforce::api
