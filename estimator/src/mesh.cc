#include "tactforce/estimator/mesh.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>

#include <Eigen/Geometry>

#include "absl/strings/str_cat.h"

namespace tactforce::estimator {
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

absl::StatusOr<TriangleMesh> ReadObj(std::istream& in, const std::string& path) {
  TriangleMesh mesh;
  std::string line;
  int line_number = 0;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream ls(line);
    std::string tag;
    if (!(ls >> tag) || tag[0] == '#') continue;
    if (tag == "v") {
      Vector3d v;
      if (!(ls >> v.x() >> v.y() >> v.z()))
        return absl::InvalidArgumentError(absl::StrCat(path, ":", line_number, ": bad vertex"));
      mesh.vertices.push_back(v);
    } else if (tag == "f") {
      std::vector<int> idx;
      std::string token;
      while (ls >> token) {
        try {
          int i = std::stoi(token.substr(0, token.find('/')));
          i = i < 0 ? static_cast<int>(mesh.vertices.size()) + i : i - 1;  // OBJ is 1-based
          idx.push_back(i);
        } catch (...) {
          return absl::InvalidArgumentError(
              absl::StrCat(path, ":", line_number, ": bad face index '", token, "'"));
        }
      }
      if (idx.size() < 3)
        return absl::InvalidArgumentError(absl::StrCat(path, ":", line_number, ": face with < 3 vertices"));
      for (size_t k = 1; k + 1 < idx.size(); ++k) mesh.triangles.push_back({idx[0], idx[k], idx[k + 1]});
    }
  }
  return mesh;
}

absl::StatusOr<TriangleMesh> ReadStl(const std::string& bytes, const std::string& path) {
  TriangleMesh mesh;
  auto add = [&](const Vector3d& a, const Vector3d& b, const Vector3d& c) {
    const int base = static_cast<int>(mesh.vertices.size());
    mesh.vertices.insert(mesh.vertices.end(), {a, b, c});
    mesh.triangles.push_back({base, base + 1, base + 2});
  };
  if (bytes.size() >= 84) {
    uint32_t count = 0;
    std::memcpy(&count, bytes.data() + 80, 4);
    if (bytes.size() == 84 + 50ull * count) {  // binary
      for (uint32_t t = 0; t < count; ++t) {
        const char* rec = bytes.data() + 84 + 50ull * t + 12;  // skip the normal
        float v[9];
        std::memcpy(v, rec, sizeof(v));
        add(Vector3d(v[0], v[1], v[2]), Vector3d(v[3], v[4], v[5]), Vector3d(v[6], v[7], v[8]));
      }
      return mesh;
    }
  }
  std::istringstream in(bytes);
  std::string line, word;
  int line_number = 0;
  std::vector<Vector3d> facet;
  while (std::getline(in, line)) {
    ++line_number;
    std::istringstream ls(line);
    if (!(ls >> word)) continue;
    if (word == "vertex") {
      Vector3d v;
      if (!(ls >> v.x() >> v.y() >> v.z()))
        return absl::InvalidArgumentError(absl::StrCat(path, ":", line_number, ": bad vertex"));
      facet.push_back(v);
    } else if (word == "endfacet") {
      if (facet.size() != 3)
        return absl::InvalidArgumentError(
            absl::StrCat(path, ":", line_number, ": facet with ", facet.size(), " vertices"));
      add(facet[0], facet[1], facet[2]);
      facet.clear();
    }
  }
  if (mesh.triangles.empty())
    return absl::InvalidArgumentError(absl::StrCat(path, ": not an STL file (no facets)"));
  return mesh;
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
      return absl::InvalidArgumentError(absl::StrCat("mesh.triangles[", t, "]: degenerate (zero area)"));
  }
  return absl::OkStatus();
}

absl::StatusOr<TriangleMesh> ReadMeshFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::InvalidArgumentError(absl::StrCat(path, ": cannot open"));
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string lower = path;
  std::transform(lower.begin(), lower.end(), lower.begin(), ::tolower);
  absl::StatusOr<TriangleMesh> mesh;
  if (lower.size() > 4 && lower.substr(lower.size() - 4) == ".obj") {
    std::istringstream s(bytes);
    mesh = ReadObj(s, path);
  } else if (lower.size() > 4 && lower.substr(lower.size() - 4) == ".stl") {
    mesh = ReadStl(bytes, path);
  } else {
    return absl::InvalidArgumentError(absl::StrCat(path, ": unknown mesh format (use .stl or .obj)"));
  }
  if (!mesh.ok()) return mesh.status();
  if (absl::Status s = ValidateMesh(*mesh); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat(path, ": ", s.message()));
  return mesh;
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

}  // namespace tactforce::estimator
