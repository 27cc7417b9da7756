// The probe experiment's data (probe.h): built-in surface pairs and boxes,
// a box from JSON (errors name the field), validation and the box mesh.
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "tactforce/experiment/probe.h"
#include "tactforce/io/json.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

using Eigen::Vector3d;

absl::Status Bad(const std::string& field, const std::string& why) {
  return absl::InvalidArgumentError(absl::StrCat(field, ": ", why));
}

// A JSON array of three finite numbers.
absl::StatusOr<Vector3d> Vec3Field(const io::JsonValue& v, const std::string& where) {
  if (!v.is_array() || v.array().size() != 3)
    return Bad(where, "must be an array of 3 numbers (m)");
  Vector3d out;
  for (int k = 0; k < 3; ++k) {
    if (!v.array()[k].is_number()) return Bad(absl::StrCat(where, "[", k, "]"), "must be a number");
    out[k] = v.array()[k].number();
  }
  return out;
}

std::string At(const std::string& source, const io::JsonValue& v) {
  return absl::StrCat(source, ":", v.line(), ": ");
}

}  // namespace

const std::vector<SurfacePair>& BuiltInSurfaces() {
  static const std::vector<SurfacePair>* const s = new std::vector<SurfacePair>{
      {"silicone/glass", 0.30},         {"silicone/acrylic", 0.36},
      {"silicone/painted-metal", 0.42}, {"silicone/abs", 0.48},
      {"silicone/pla", 0.55},           {"silicone/hardwood", 0.62},
      {"silicone/cardboard", 0.69},     {"silicone/paper-label", 0.76},
      {"silicone/matte-plastic", 0.84}, {"silicone/rubber", 0.92},
      {"silicone/foam", 1.00},
  };
  return *s;
}

const std::vector<ProbeObject>& BuiltInProbeObjects() {
  static const std::vector<ProbeObject>* const o = new std::vector<ProbeObject>{
      {"box", Vector3d(0.08, 0.06, 0.05), 0.15, Vector3d::Zero()},
      // YCB-like: a wood block lying down, a sugar box, a light box with its CoM off-centre.
      {"wood-block", Vector3d(0.085, 0.085, 0.06), 0.25, Vector3d::Zero()},
      {"sugar-box", Vector3d(0.09, 0.04, 0.09), 0.20, Vector3d::Zero()},
      {"offset-box", Vector3d(0.10, 0.05, 0.04), 0.12, Vector3d(0.015, -0.008, 0.005)},
  };
  return *o;
}

absl::Status ValidateProbeObject(const ProbeObject& o) {
  for (int k = 0; k < 3; ++k)
    if (!(o.size[k] >= 0.03 && o.size[k] <= 0.3))
      return Bad(absl::StrCat("size[", k, "]"),
                 absl::StrFormat("must be in [0.03, 0.3] m, got %g", o.size[k]));
  if (!(o.mass >= 0.01 && o.mass <= 2))
    return Bad("mass", absl::StrFormat("must be in [0.01, 2] kg, got %g", o.mass));
  for (int k = 0; k < 3; ++k)
    if (!(std::abs(o.com_offset[k]) <= 0.4 * o.size[k]))
      return Bad(
          absl::StrCat("com_offset[", k, "]"),
          absl::StrFormat("must be inside the box (|x| <= 0.4 size), got %g", o.com_offset[k]));
  return absl::OkStatus();
}

absl::StatusOr<ProbeObject> FindProbeObject(const std::string& name) {
  std::vector<std::string> names;
  for (const ProbeObject& o : BuiltInProbeObjects()) {
    if (o.name == name) return o;
    names.push_back(o.name);
  }
  return absl::NotFoundError(absl::StrCat(
      "unknown object '", name, "' (built-ins: ", absl::StrJoin(names, ", "), "; or a JSON file)"));
}

absl::StatusOr<ProbeObject> ProbeObjectFromJson(const std::string& text,
                                                const std::string& source) {
  TF_ASSIGN_OR_RETURN(io::JsonValue doc, io::ParseJson(text, source));
  if (!doc.is_object())
    return Bad(source, "must be a JSON object {\"size\": [x, y, z], \"mass\": m}");
  ProbeObject o;
  o.name = source;
  bool has_size = false, has_mass = false;
  for (const auto& [key, v] : doc.members()) {
    const std::string at = At(source, v);
    if (key == "name") {
      if (!v.is_string()) return Bad(at + "name", "must be a string");
      o.name = v.string();
    } else if (key == "size" || key == "com_offset") {
      TF_ASSIGN_OR_RETURN(Vector3d x, Vec3Field(v, at + key));
      (key == "size" ? o.size : o.com_offset) = x;
      has_size = has_size || key == "size";
    } else if (key == "mass") {
      if (!v.is_number()) return Bad(at + "mass", "must be a number (kg)");
      o.mass = v.number();
      has_mass = true;
    } else {
      return Bad(at + key, "unknown field (expected name, size, mass, com_offset)");
    }
  }
  if (!has_size) return Bad(source + ": size", "missing");
  if (!has_mass) return Bad(source + ": mass", "missing");
  TF_RETURN_IF_ERROR(io::PrependPath(ValidateProbeObject(o), source));
  return o;
}

io::TriangleMesh BoxMesh(const Vector3d& size) {
  io::TriangleMesh m;
  const Vector3d h = size / 2;
  for (int k = 0; k < 8; ++k)
    m.vertices.emplace_back(k & 1 ? h.x() : -h.x(), k & 2 ? h.y() : -h.y(), k & 4 ? h.z() : -h.z());
  // Counter-clockwise seen from outside.
  m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  return m;
}

}  // namespace tactforce::experiment
