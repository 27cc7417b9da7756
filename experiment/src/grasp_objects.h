// Internal (not installed): the graspable objects as data. One
// ObjectSpec per GraspObject says where its finger layout comes from, how its
// inertia follows from its mass, how it rests on the table, whether the hand
// lifts or pivots it, and its MJCF geometry; GraspSetup::Create looks the
// object up and builds the plans and the scene from the spec.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/experiment/grasp.h"
#include "tactforce/planner/types.h"

namespace tactforce::experiment {

// One MJCF geom of the object, in the object frame (rendered as
// <geom name="objK" type=... [pos=...] size=... rgba=.../>).
struct GeomSpec {
  std::string type;          // MuJoCo geom type: "sphere", "box", "cylinder"
  std::vector<double> size;  // MuJoCo's size: radius; half extents; radius and half height (m)
  std::optional<planner::Vec3> pos;  // m; absent: at the object origin
  std::string rgba;
};

struct ObjectSpec {
  GraspObject object = GraspObject::kSphere;
  // Finger layout, mass, CoM, sigmas and plan options: the planner's built-in
  // grasp of this name; empty: `contacts` and `mass` with default plan options.
  std::string built_in_grasp = {};
  std::vector<planner::Contact> contacts = {};  // intrinsic (fingers) first, then extrinsic
  double mass = 0;                              // kg
  // Inertia about the CoM (kg m^2) given the object's mass.
  std::function<planner::Inertia(double mass)> inertia = {};
  planner::Vec3 rest_origin = planner::Vec3::Zero();  // object origin on the table (world, m)
  // Set: the hand pivots the object about +x through this world point
  // (pivot_angle_deg) instead of lifting it (lift_height).
  std::optional<planner::Vec3> pivot_point = {};
  std::vector<GeomSpec> geoms = {};
  double table_mu = 0.6;  // object/table friction
};

// The spec of `object` from the table; nullptr if the table lacks it.
const ObjectSpec* FindObjectSpec(GraspObject object);

// The spec's MJCF geoms, `name="obj<K>"` in order, each a complete <geom .../>.
std::vector<std::string> GeomElements(const ObjectSpec& spec);

// The object's grasp problem (object frame) and plan options: the built-in
// grasp's, or the spec's contacts and mass. Internal error when a named
// built-in grasp is missing from the planner.
struct ObjectGrasp {
  planner::PlanProblem problem;
  planner::PlanOptions options;
};
absl::StatusOr<ObjectGrasp> ResolveGrasp(const ObjectSpec& spec);

}  // namespace tactforce::experiment
