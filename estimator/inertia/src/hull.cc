#include "tactforce/inertia/hull.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <set>
#include <utility>

#include "absl/strings/str_cat.h"

namespace tactforce::inertia {

double ConvexHull::SignedDistanceBound(const Vec3& x) const {
  double worst = -std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < normals.size(); ++j) worst = std::max(worst, normals[j].dot(x) - offsets[j]);
  return worst;
}

bool ConvexHull::Contains(const Vec3& x, double tolerance) const {
  return SignedDistanceBound(x) <= tolerance * std::max(size, 1e-300);
}

absl::StatusOr<ConvexHull> ComputeConvexHull(const std::vector<Vec3>& pts) {
  const int n = static_cast<int>(pts.size());
  if (n < 4) {
    return absl::InvalidArgumentError(
        absl::StrCat("hull: ", n, " vertices; at least 4 non-coplanar vertices are needed"));
  }
  Vec3 lo = pts[0], hi = pts[0];
  for (int i = 0; i < n; ++i) {
    if (!pts[i].allFinite()) return absl::InvalidArgumentError(absl::StrCat("hull[", i, "]: not finite"));
    lo = lo.cwiseMin(pts[i]);
    hi = hi.cwiseMax(pts[i]);
  }
  const double size = (hi - lo).norm();
  if (!(size > 0)) return absl::InvalidArgumentError("hull: all vertices coincide");
  const double eps = 1e-10 * size;

  // Initial tetrahedron from extreme points.
  int i0 = 0;
  for (int i = 1; i < n; ++i)
    if (pts[i].x() < pts[i0].x()) i0 = i;
  int i1 = -1;
  double best = 0;
  for (int i = 0; i < n; ++i) {
    const double d = (pts[i] - pts[i0]).norm();
    if (d > best) best = d, i1 = i;
  }
  if (i1 < 0 || best <= eps) return absl::InvalidArgumentError("hull: all vertices coincide");
  const Vec3 axis = (pts[i1] - pts[i0]).normalized();
  int i2 = -1;
  best = 0;
  for (int i = 0; i < n; ++i) {
    const double d = (pts[i] - pts[i0]).cross(axis).norm();
    if (d > best) best = d, i2 = i;
  }
  if (i2 < 0 || best <= 1e-9 * size)
    return absl::InvalidArgumentError("hull: degenerate: all vertices are collinear");
  const Vec3 pn = (pts[i1] - pts[i0]).cross(pts[i2] - pts[i0]).normalized();
  int i3 = -1;
  best = 0;
  for (int i = 0; i < n; ++i) {
    const double d = std::abs(pn.dot(pts[i] - pts[i0]));
    if (d > best) best = d, i3 = i;
  }
  if (i3 < 0 || best <= 1e-9 * size)
    return absl::InvalidArgumentError("hull: degenerate: all vertices are coplanar (a flat object has no volume)");

  const Vec3 interior = 0.25 * (pts[i0] + pts[i1] + pts[i2] + pts[i3]);
  struct Face {
    std::array<int, 3> v;
    Vec3 n;
    double d;
  };
  auto make = [&](int a, int b, int c) {
    Face f;
    f.v = {a, b, c};
    f.n = (pts[b] - pts[a]).cross(pts[c] - pts[a]);
    const double len = f.n.norm();
    f.n = len > 0 ? Vec3(f.n / len) : Vec3::Zero();
    f.d = f.n.dot(pts[a]);
    if (f.n.dot(interior) > f.d) {  // inward: flip
      std::swap(f.v[1], f.v[2]);
      f.n = -f.n;
      f.d = -f.d;
    }
    return f;
  };
  std::vector<Face> faces = {make(i0, i1, i2), make(i0, i1, i3), make(i0, i2, i3), make(i1, i2, i3)};

  for (int p = 0; p < n; ++p) {
    if (p == i0 || p == i1 || p == i2 || p == i3) continue;
    std::vector<char> visible(faces.size(), 0);
    bool any = false;
    for (size_t f = 0; f < faces.size(); ++f) {
      if (faces[f].n.dot(pts[p]) - faces[f].d > eps) visible[f] = 1, any = true;
    }
    if (!any) continue;
    std::set<std::pair<int, int>> edges;
    for (size_t f = 0; f < faces.size(); ++f) {
      if (!visible[f]) continue;
      const auto& v = faces[f].v;
      for (int k = 0; k < 3; ++k) edges.insert({v[k], v[(k + 1) % 3]});
    }
    std::vector<Face> kept;
    kept.reserve(faces.size() + edges.size());
    for (size_t f = 0; f < faces.size(); ++f)
      if (!visible[f]) kept.push_back(faces[f]);
    for (const auto& [a, b] : edges) {
      if (edges.count({b, a})) continue;  // interior edge of the visible region
      Face f;
      f.v = {a, b, p};
      f.n = (pts[b] - pts[a]).cross(pts[p] - pts[a]);
      const double len = f.n.norm();
      if (!(len > 0)) continue;
      f.n /= len;
      f.d = f.n.dot(pts[a]);
      kept.push_back(f);
    }
    faces = std::move(kept);
  }

  ConvexHull hull;
  hull.size = size;
  std::set<int> used;
  for (const Face& f : faces) {
    if (f.n.squaredNorm() == 0) continue;
    hull.normals.push_back(f.n);
    hull.offsets.push_back(f.d);
    for (int v : f.v) used.insert(v);
  }
  for (int v : used) hull.vertices.push_back(pts[v]);
  return hull;
}

}  // namespace tactforce::inertia
