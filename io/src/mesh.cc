// Meshes in the object frame (mesh.h): validation, placement (scale and pose),
// descriptor JSON read with nlohmann's DOM, LoadMesh for the CLI's --mesh,
// and the nearest triangle to a point.
#include "tactforce/io/mesh.h"

#include <cmath>
#include <filesystem>
#include <limits>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::io {
namespace {

using Eigen::Vector3d;

// Closest point on triangle abc to p (region tests on barycentric coordinates).
Vector3d ClosestOnTriangle(const Vector3d& p, const Vector3d& a, const Vector3d& b,
                           const Vector3d& c) {
  const Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1.0 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

// Placement checks shared by ValidatePlacement and the descriptor reader;
// `field` starts the message.
absl::Status CheckScale(double scale, const std::string& field) {
  if (std::isfinite(scale) && scale > 0) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(field, ": must be > 0 (got ", scale, ")"));
}

absl::Status CheckPosition(const Vector3d& p, const std::string& field) {
  if (p.allFinite()) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(field, ": not finite"));
}

absl::Status CheckQuaternion(const Eigen::Quaterniond& q, const std::string& field) {
  if (!q.coeffs().allFinite())
    return absl::InvalidArgumentError(absl::StrCat(field, ": not finite"));
  if (q.norm() >= 1e-6) return absl::OkStatus();
  return absl::InvalidArgumentError(
      absl::StrCat(field, ": quaternion norm ", q.norm(), " is near zero (must be >= 1e-6)"));
}

using Json = nlohmann::json;

absl::Status KeyError(const std::string& path, absl::string_view what) {
  return absl::InvalidArgumentError(absl::StrCat(path, ": ", what));
}

// `n` finite numbers from a JSON array at `key`.
absl::StatusOr<std::vector<double>> Numbers(const Json& j, size_t n, const std::string& path,
                                            const std::string& key, const std::string& what) {
  if (!j.is_array() || j.size() != n)
    return KeyError(
        path,
        absl::StrCat("'", key, "' must be an array of ", n, " numbers ", what, " (got ",
                     j.is_array() ? absl::StrCat(j.size(), " elements") : j.type_name(), ")"));
  std::vector<double> out;
  for (size_t i = 0; i < n; ++i) {
    if (!j[i].is_number())
      return KeyError(
          path, absl::StrCat("'", key, "[", i, "]' must be a number (got ", j[i].type_name(), ")"));
    out.push_back(j[i].get<double>());
    if (!std::isfinite(out.back()))
      return KeyError(path, absl::StrCat("'", key, "[", i, "]' is not finite"));
  }
  return out;
}

// The descriptor as nlohmann's DOM; a syntax error is
// "path:line:column: JSON syntax error ..." (nlohmann's wording).
absl::StatusOr<Json> ParseDescriptorJson(const std::string& text, const std::string& path) {
  try {
    return Json::parse(text);
  } catch (const Json::parse_error& e) {
    // e.byte counts the bytes read, the offending one last.
    const TextPosition at = PositionInText(text, e.byte > 0 ? e.byte - 1 : 0);
    std::string what = e.what();
    if (const size_t p = what.find("syntax error"); p != std::string::npos) what = what.substr(p);
    return absl::InvalidArgumentError(
        absl::StrCat(path, ":", at.line, ":", at.column, ": JSON ", what));
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": JSON: ", e.what()));
  }
}

}  // namespace

absl::Status ValidateMesh(const TriangleMesh& mesh) {
  if (mesh.triangles.empty()) return absl::InvalidArgumentError("mesh.triangles: empty");
  for (size_t v = 0; v < mesh.vertices.size(); ++v) {
    if (!mesh.vertices[v].allFinite())
      return absl::InvalidArgumentError(absl::StrCat("mesh.vertices[", v, "]: not finite"));
  }
  const int n = static_cast<int>(mesh.vertices.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    for (int i : mesh.triangles[t]) {
      if (i < 0 || i >= n)
        return absl::InvalidArgumentError(absl::StrCat("mesh.triangles[", t, "]: vertex index ", i,
                                                       " out of range (", n, " vertices)"));
    }
    const auto& [a, b, c] = mesh.triangles[t];
    const double area2 =
        (mesh.vertices[b] - mesh.vertices[a]).cross(mesh.vertices[c] - mesh.vertices[a]).norm();
    if (!(area2 > 1e-18))
      return absl::InvalidArgumentError(
          absl::StrCat("mesh.triangles[", t, "]: degenerate (zero area)"));
  }
  return absl::OkStatus();
}

absl::Status ValidatePlacement(const MeshPlacement& placement, std::string_view field_view) {
  const std::string field(field_view);
  TF_RETURN_IF_ERROR(CheckScale(placement.scale, absl::StrCat(field, ".scale")));
  TF_RETURN_IF_ERROR(CheckPosition(placement.position, absl::StrCat(field, ".position")));
  return CheckQuaternion(placement.orientation, absl::StrCat(field, ".orientation"));
}

TriangleMesh TransformToObjectFrame(const TriangleMesh& mesh, const MeshPlacement& placement) {
  const Eigen::Matrix3d Rt = placement.orientation.normalized().toRotationMatrix().transpose();
  TriangleMesh out = mesh;
  for (Vector3d& v : out.vertices) v = Rt * (placement.scale * v - placement.position);
  return out;
}

absl::StatusOr<MeshDescriptor> ReadMeshDescriptor(const std::string& path) {
  TF_ASSIGN_OR_RETURN(std::string text, ReadTextFile(path));
  TF_ASSIGN_OR_RETURN(Json json, ParseDescriptorJson(text, path));
  const Json& j = json;
  if (!j.is_object())
    return KeyError(path, absl::StrCat("expected a JSON object (got ", j.type_name(), ")"));
  for (const auto& [key, value] : j.items()) {
    if (key != "mesh" && key != "scale" && key != "object_in_mesh")
      return KeyError(
          path, absl::StrCat("unknown key '", key, "' (expected mesh, scale, object_in_mesh)"));
  }
  MeshDescriptor d;
  const auto mesh = j.find("mesh");
  if (mesh == j.end())
    return KeyError(path, "missing key 'mesh' (the mesh file, .stl, .obj or .ply)");
  if (!mesh->is_string() || mesh->get_ref<const std::string&>().empty())
    return KeyError(path, absl::StrCat("'mesh' must be a non-empty string (got ",
                                       mesh->is_string() ? "\"\"" : mesh->type_name(), ")"));
  const std::filesystem::path file = mesh->get<std::string>();
  d.mesh_path = file.is_absolute() ? file.string()
                                   : (std::filesystem::path(path).parent_path() / file).string();
  if (const auto scale = j.find("scale"); scale != j.end()) {
    if (!scale->is_number())
      return KeyError(path,
                      absl::StrCat("'scale' must be a number (got ", scale->type_name(), ")"));
    d.placement.scale = scale->get<double>();
    if (absl::Status s = CheckScale(d.placement.scale, "scale"); !s.ok())
      return KeyError(path, s.message());
  }
  if (const auto pose = j.find("object_in_mesh"); pose != j.end()) {
    if (!pose->is_object())
      return KeyError(
          path,
          absl::StrCat("'object_in_mesh' must be an object with position and quaternion (got ",
                       pose->type_name(), ")"));
    for (const auto& [key, value] : pose->items()) {
      if (key != "position" && key != "quaternion")
        return KeyError(path, absl::StrCat("unknown key 'object_in_mesh.", key,
                                           "' (expected position, quaternion)"));
    }
    if (const auto p = pose->find("position"); p != pose->end()) {
      TF_ASSIGN_OR_RETURN(std::vector<double> v,
                          Numbers(*p, 3, path, "object_in_mesh.position", "[x, y, z]"));
      d.placement.position = Vector3d(v[0], v[1], v[2]);
    }
    if (const auto q = pose->find("quaternion"); q != pose->end()) {
      TF_ASSIGN_OR_RETURN(std::vector<double> v,
                          Numbers(*q, 4, path, "object_in_mesh.quaternion", "[w, x, y, z]"));
      d.placement.orientation = Eigen::Quaterniond(v[0], v[1], v[2], v[3]);
      if (absl::Status s = CheckQuaternion(d.placement.orientation, "object_in_mesh.quaternion");
          !s.ok())
        return KeyError(path, s.message());
    }
  }
  return d;
}

absl::StatusOr<LoadedMesh> LoadMesh(const MeshRequest& request) {
  LoadedMesh out;
  const std::string ext =
      absl::AsciiStrToLower(std::filesystem::path(request.path).extension().string());
  if (ext == ".json") {
    TF_ASSIGN_OR_RETURN(MeshDescriptor d, ReadMeshDescriptor(request.path));
    out.mesh_path = d.mesh_path;
    out.placement = d.placement;
  } else {
    out.mesh_path = request.path;
  }
  if (request.scale) out.placement.scale = *request.scale;
  if (request.pose) {
    out.placement.position = request.pose->position;
    out.placement.orientation = request.pose->orientation;
  }
  TF_RETURN_IF_ERROR(ValidatePlacement(out.placement));
  TF_ASSIGN_OR_RETURN(std::string format, MeshFormatFromPath(out.mesh_path));
  TF_ASSIGN_OR_RETURN(TriangleMesh mesh, ReadMeshFile(out.mesh_path));
  out.format = format;
  out.name = std::filesystem::path(out.mesh_path).filename().string();
  out.placement.orientation.normalize();
  out.mesh = TransformToObjectFrame(mesh, out.placement);
  return out;
}

NearestTriangle FindNearestTriangle(const TriangleMesh& mesh, const Vector3d& point) {
  NearestTriangle best;
  best.distance = std::numeric_limits<double>::infinity();
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const auto& [ia, ib, ic] = mesh.triangles[t];
    const Vector3d& a = mesh.vertices[ia];
    const Vector3d& b = mesh.vertices[ib];
    const Vector3d& c = mesh.vertices[ic];
    const Vector3d q = ClosestOnTriangle(point, a, b, c);
    const double d = (q - point).norm();
    if (d < best.distance) {
      best.distance = d;
      best.triangle = static_cast<int>(t);
      best.closest = q;
      best.inward_normal = -(b - a).cross(c - a).normalized();
    }
  }
  return best;
}

}  // namespace tactforce::io
