// The table of graspable objects (grasp_objects.h): the sphere, the wrench
// and the cylinder reuse the planner's built-in grasps (contacts, sigmas,
// minimum normal force, plan options); the cube lists its own two fingertips
// and the two corners of the bottom edge it pivots on (extrinsic table
// contacts). Inertias are those of the uniform solids, except the wrench's,
// which is the one the planner's wrench trajectory uses.
#include "grasp_objects.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "tactforce/planner/examples.h"
#include "tactforce/planner/trajectory.h"

namespace tactforce::experiment {
namespace {

using planner::Vec3;

planner::Inertia Isotropic(double I) { return {I, I, I, 0, 0, 0}; }

planner::Contact Fingertip(const char* name, const Vec3& position, const Vec3& normal, double mu) {
  planner::Contact c;
  c.name = name;
  c.position = position;
  c.normal = normal;
  c.friction = mu;
  c.kind = planner::ContactKind::kIntrinsic;
  c.sigma = 0.3;
  c.min_normal_force = 0.3;
  return c;
}

planner::Contact TableContact(const char* name, const Vec3& position, double mu) {
  planner::Contact c;
  c.name = name;
  c.position = position;
  c.normal = Vec3::UnitZ();
  c.friction = mu;
  c.kind = planner::ContactKind::kExtrinsic;
  return c;
}

constexpr double kSphereRadius = 0.035;  // m
constexpr double kWrenchHalfThickness = 0.008;
constexpr double kCylinderRadius = 0.055, kCylinderHeight = 0.12;
constexpr double kCubeHalfEdge = 0.04, kCubeMass = 0.15;

std::vector<ObjectSpec> MakeObjectSpecs() {
  const double a = kCubeHalfEdge;
  return {
      {.object = GraspObject::kSphere,
       .built_in_grasp = "sphere-pinch",
       .inertia = [](double m) { return Isotropic(0.4 * m * kSphereRadius * kSphereRadius); },
       .rest_origin = Vec3(0, 0, kSphereRadius),
       .geoms = {{"sphere", {kSphereRadius}, {}, "0.8 0.3 0.3 1"}}},
      // Handle 18 cm x 24 mm x 16 mm along x, a head at +x.
      {.object = GraspObject::kWrench,
       .built_in_grasp = "wrench-3f",
       .inertia = [](double) { return *planner::WrenchLiftAndRotate(2).inertia; },
       .rest_origin = Vec3(0, 0, kWrenchHalfThickness),
       .geoms = {{"box", {0.09, 0.012, kWrenchHalfThickness}, {}, "0.6 0.6 0.7 1"},
                 {"box", {0.025, 0.03, kWrenchHalfThickness}, Vec3(0.11, 0, 0), "0.6 0.6 0.7 1"}}},
      {.object = GraspObject::kCylinder,
       .built_in_grasp = "cylinder-4f",
       .inertia =
           [](double m) {
             const double r = kCylinderRadius, h = kCylinderHeight;
             const double ixx = m * (3 * r * r + h * h) / 12, izz = 0.5 * m * r * r;
             return planner::Inertia{ixx, ixx, izz, 0, 0, 0};
           },
       .rest_origin = Vec3(0, 0, kCylinderHeight / 2),
       .geoms = {{"cylinder", {kCylinderRadius, kCylinderHeight / 2}, {}, "0.3 0.6 0.3 1"}}},
      // Two fingertips on the +-x faces, above the centre and towards +y (the
      // side that rises); the cube pivots about its bottom edge at y = -a.
      {.object = GraspObject::kCube,
       .contacts = {Fingertip("thumb", Vec3(-a, 0.02, 0.02), Vec3::UnitX(), 0.8),
                    Fingertip("index", Vec3(a, 0.02, 0.02), -Vec3::UnitX(), 0.8),
                    TableContact("edge-left", Vec3(-a, -a, -a), 0.6),
                    TableContact("edge-right", Vec3(a, -a, -a), 0.6)},
       .mass = kCubeMass,
       .inertia =
           [](double m) { return Isotropic(m * (2 * kCubeHalfEdge) * (2 * kCubeHalfEdge) / 6); },
       .rest_origin = Vec3(0, 0, a),
       .pivot_point = Vec3(0, -a, 0),
       .geoms = {{"box", {a, a, a}, {}, "0.3 0.3 0.8 1"}}},
  };
}

}  // namespace

const ObjectSpec* FindObjectSpec(GraspObject object) {
  static const std::vector<ObjectSpec>* const specs =
      new std::vector<ObjectSpec>(MakeObjectSpecs());
  for (const ObjectSpec& spec : *specs)
    if (spec.object == object) return &spec;
  return nullptr;
}

std::vector<std::string> GeomElements(const ObjectSpec& spec) {
  std::vector<std::string> out;
  for (size_t k = 0; k < spec.geoms.size(); ++k) {
    const GeomSpec& g = spec.geoms[k];
    const std::string pos =
        g.pos ? absl::StrFormat(" pos=\"%g %g %g\"", g.pos->x(), g.pos->y(), g.pos->z()) : "";
    const std::string size = absl::StrJoin(
        g.size, " ", [](std::string* out, double v) { absl::StrAppendFormat(out, "%g", v); });
    out.push_back(absl::StrFormat("<geom name=\"obj%d\" type=\"%s\"%s size=\"%s\" rgba=\"%s\"/>", k,
                                  g.type, pos, size, g.rgba));
  }
  return out;
}

absl::StatusOr<ObjectGrasp> ResolveGrasp(const ObjectSpec& spec) {
  ObjectGrasp out;
  if (spec.built_in_grasp.empty()) {
    out.problem.object.mass = spec.mass;
    out.problem.contacts = spec.contacts;
    return out;
  }
  for (const planner::ExampleGrasp& g : planner::BuiltInGrasps()) {
    if (g.name == spec.built_in_grasp) {
      out.problem = g.problem;
      out.options = g.options;
      return out;
    }
  }
  return absl::InternalError(absl::StrCat("built-in grasp '", spec.built_in_grasp, "' missing"));
}

}  // namespace tactforce::experiment
