// Does a triangle mesh bound a solid: edge topology, orientation, degenerate
// faces and the enclosed volume.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "absl/strings/str_cat.h"
#include "tactforce/io/mesh.h"

namespace tactforce::io {
namespace {

// A face is degenerate when its height is below this fraction of its longest edge.
constexpr double kDegenerateRatio = 1e-10;
// RequireClosedSolid rejects meshes whose degenerate faces carry more area.
constexpr double kMaxDegenerateAreaFraction = 0.01;

}  // namespace

MeshCheck CheckMesh(const TriangleMesh& mesh) {
  MeshCheck c;
  c.vertices = static_cast<int>(mesh.vertices.size());
  c.faces = static_cast<int>(mesh.triangles.size());
  const int n = c.vertices;

  // Undirected edge (low << 32 | high) with bit 0 of `forward` = traversed low -> high.
  struct EdgeUse {
    uint64_t key;
    bool forward;
  };
  std::vector<EdgeUse> edges;
  edges.reserve(3 * mesh.triangles.size());
  double degenerate_area = 0.0;
  for (const auto& t : mesh.triangles) {
    if (std::any_of(t.begin(), t.end(), [n](int i) { return i < 0 || i >= n; })) {
      ++c.degenerate_faces;
      continue;
    }
    const Eigen::Vector3d& a = mesh.vertices[t[0]];
    const Eigen::Vector3d& b = mesh.vertices[t[1]];
    const Eigen::Vector3d& d = mesh.vertices[t[2]];
    const double area = 0.5 * (b - a).cross(d - a).norm();
    const double longest2 =
        std::max({(b - a).squaredNorm(), (d - b).squaredNorm(), (a - d).squaredNorm()});
    c.area += area;
    c.volume += a.dot(b.cross(d)) / 6.0;
    if (!(2.0 * area > kDegenerateRatio * longest2) || longest2 == 0.0) {
      ++c.degenerate_faces;
      degenerate_area += area;
    }
    // A collapsed triangle (repeated index) contributes no edges.
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
    for (int k = 0; k < 3; ++k) {
      const uint32_t from = static_cast<uint32_t>(t[k]), to = static_cast<uint32_t>(t[(k + 1) % 3]);
      const uint64_t lo = std::min(from, to), hi = std::max(from, to);
      edges.push_back({lo << 32 | hi, from < to});
    }
  }
  std::sort(edges.begin(), edges.end(),
            [](const EdgeUse& x, const EdgeUse& y) { return x.key < y.key; });
  for (size_t i = 0; i < edges.size();) {
    size_t j = i;
    int forward = 0;
    for (; j < edges.size() && edges[j].key == edges[i].key; ++j) forward += edges[j].forward;
    const int uses = static_cast<int>(j - i);
    if (uses == 1)
      ++c.boundary_edges;
    else if (uses == 2 && forward != 1)
      ++c.inconsistent_edges;
    else if (uses > 2 && 2 * forward != uses)
      ++c.non_manifold_edges;
    else if (uses > 2)
      ++c.junction_edges;
    i = j;
  }
  if (c.area > 0)
    c.degenerate_area_fraction = degenerate_area / c.area;
  else if (c.degenerate_faces > 0)
    c.degenerate_area_fraction = 1.0;
  c.closed = c.boundary_edges == 0 && c.non_manifold_edges == 0;
  c.consistently_oriented = c.inconsistent_edges == 0;
  return c;
}

absl::Status RequireClosedSolid(const MeshCheck& c, std::string_view name_view) {
  const std::string name(name_view);
  if (c.faces == 0) return absl::InvalidArgumentError(absl::StrCat(name, ": no triangles"));
  if (c.non_manifold_edges > 0)
    return absl::InvalidArgumentError(absl::StrCat(
        name, ": ", c.non_manifold_edges,
        " non-manifold edges (shared by more than two triangles, not as many in each direction)"));
  if (c.boundary_edges > 0)
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": ", c.boundary_edges, " boundary edges: the mesh is not closed"));
  if (c.inconsistent_edges > 0)
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": ", c.inconsistent_edges,
                     " edges are traversed twice in the same direction: the triangles are not "
                     "consistently oriented"));
  if (c.degenerate_area_fraction > kMaxDegenerateAreaFraction)
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": ", c.degenerate_faces, " degenerate (zero-area) faces carry ",
                     100.0 * c.degenerate_area_fraction, " % of the area (more than 1 %)"));
  if (c.volume < 0)
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": volume ", c.volume,
                     " m^3 is negative: the mesh is inside out (flip the winding)"));
  if (!(c.volume > 0))
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": volume ", c.volume, " m^3 is not positive"));
  return absl::OkStatus();
}

}  // namespace tactforce::io
