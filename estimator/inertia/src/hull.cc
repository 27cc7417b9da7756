// Convex hulls of the object's points (hull.h) with Debian's reentrant qhull:
// the input is checked (enough finite points, not flat), each merged facet
// becomes one half-space, and containment is tested against them.
#include "tactforce/inertia/hull.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include "absl/strings/str_cat.h"
#include "absl/strings/strip.h"

extern "C" {
#include <libqhull_r/qhull_ra.h>
}

namespace tactforce::inertia {
namespace {

// The hull of `pts` (already checked: >= 4 finite, not flat) with Debian's
// reentrant qhull. Default options: coplanar facets merged (C-0), so each
// face of the hull is one half-space. Qhull's messages go to a memory stream
// and only appear in the error.
absl::StatusOr<ConvexHull> QhullHull(const std::vector<Vec3>& pts, double size) {
  std::vector<coordT> coords(3 * pts.size());
  for (size_t i = 0; i < pts.size(); ++i)
    for (int k = 0; k < 3; ++k) coords[3 * i + k] = pts[i](k);
  char* log_text = nullptr;
  size_t log_size = 0;
  std::FILE* log = open_memstream(&log_text, &log_size);
  if (log == nullptr)
    return absl::InternalError("hull: cannot open a memory stream for qhull's messages");

  qhT qh_storage;
  qhT* qh = &qh_storage;
  qh_zero(qh, log);
  char options[] = "qhull";
  const int exit_code = qh_new_qhull(qh, 3, static_cast<int>(pts.size()), coords.data(), False,
                                     options, nullptr, log);
  ConvexHull hull;
  hull.size = size;
  if (exit_code == 0) {
    std::vector<char> is_vertex(pts.size(), 0);
    facetT* facet;
    vertexT* vertex;
    vertexT** vertexp;
    FORALLfacets {
      const Vec3 n(facet->normal[0], facet->normal[1], facet->normal[2]);
      double d = -facet->offset;
      FOREACHvertex_(facet->vertices) {
        const int id = qh_pointid(qh, vertex->point);
        if (id < 0 || id >= static_cast<int>(pts.size())) continue;
        is_vertex[id] = 1;
        d = std::max(d, n.dot(pts[id]));  // every hull vertex inside, exactly
      }
      hull.normals.push_back(n);
      hull.offsets.push_back(d);
    }
    for (size_t i = 0; i < pts.size(); ++i)
      if (is_vertex[i]) hull.vertices.push_back(pts[i]);
  }
  qh_freeqhull(qh, !qh_ALL);
  int current_long = 0, total_long = 0;
  qh_memfreeshort(qh, &current_long, &total_long);
  std::fclose(log);
  std::string message(log_text ? log_text : "", log_size);
  std::free(log_text);
  if (exit_code != 0 || hull.normals.size() < 4) {
    const size_t end = message.find('\n');
    message = std::string(absl::StripAsciiWhitespace(message.substr(0, end)));
    return absl::InvalidArgumentError(absl::StrCat("hull: degenerate: qhull failed (code ",
                                                   exit_code, ")", message.empty() ? "" : ": ",
                                                   message));
  }
  return hull;
}

}  // namespace

double ConvexHull::SignedDistanceBound(const Vec3& x) const {
  double worst = -std::numeric_limits<double>::infinity();
  for (size_t j = 0; j < normals.size(); ++j)
    worst = std::max(worst, normals[j].dot(x) - offsets[j]);
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
    if (!pts[i].allFinite())
      return absl::InvalidArgumentError(absl::StrCat("hull[", i, "]: not finite"));
    lo = lo.cwiseMin(pts[i]);
    hi = hi.cwiseMax(pts[i]);
  }
  const double size = (hi - lo).norm();
  if (!(size > 0)) return absl::InvalidArgumentError("hull: all vertices coincide");
  const double eps = 1e-10 * size;

  // Collinear and flat sets are rejected here, with messages people can act on;
  // qhull then only sees sets with volume.
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
    return absl::InvalidArgumentError(
        "hull: degenerate: all vertices are coplanar (a flat object has no volume)");

  return QhullHull(pts, size);
}

}  // namespace tactforce::inertia
