// Convex hull of a point set in 3-D (Debian's qhull), as half-spaces
// n_j . x <= d_j with unit outward normals. Used for the CoM-in-hull
// constraint of FACTOR_GRAPH (eq. 36) and CONSTRAINED.
#pragma once

#include <vector>

#include "absl/status/statusor.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

struct ConvexHull {
  std::vector<Vec3> normals;    // unit, outward
  std::vector<double> offsets;  // n . x <= d inside
  std::vector<Vec3> vertices;   // hull vertices (subset of the input)
  double size = 0.0;            // diagonal of the axis-aligned bounding box (m)

  // Largest n_j . x - d_j (m): <= 0 inside, > 0 outside.
  double SignedDistanceBound(const Vec3& x) const;
  bool Contains(const Vec3& x, double tolerance = 1e-9) const;
};

// InvalidArgument "hull: ..." for fewer than 4 points, non-finite points or
// a flat (coplanar) or degenerate set.
absl::StatusOr<ConvexHull> ComputeConvexHull(const std::vector<Vec3>& points);

}  // namespace tactforce::inertia
