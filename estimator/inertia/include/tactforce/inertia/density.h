// Mass properties of solids bounded by closed triangle meshes, and the
// regions over which INERTIA_METHOD_DENSITY fits a piecewise-constant,
// non-negative density. Object frame, SI units (m, kg/m^3).
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "absl/status/statusor.h"
#include "tactforce/io/mesh.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

// Unit-density volume integrals of a solid, about the object origin.
struct SolidMoments {
  double volume = 0.0;                               // m^3
  Vec3 first = Vec3::Zero();                         // integral of x dV (m^4)
  Eigen::Matrix3d second = Eigen::Matrix3d::Zero();  // integral of x x^T dV (m^5)

  Vec3 Centroid() const { return volume != 0 ? Vec3(first / volume) : Vec3::Zero(); }
  // Standard parameters [m, m c, I_origin] of the solid at `density` (kg/m^3).
  Vector10d Standard(double density = 1.0) const;
  SolidMoments& operator+=(const SolidMoments& o);
  SolidMoments& operator-=(const SolidMoments& o);
};

// Exact integrals of the polyhedron bounded by a closed, consistently
// oriented mesh (object frame, m): sums over signed tetrahedra (divergence
// theorem). An inside-out mesh gives a negative volume.
SolidMoments MeshMoments(const io::TriangleMesh& mesh);

// The same for the part of the solid inside the octant
// {x <= corner.x, y <= corner.y, z <= corner.z} of `frame` (columns = the
// octant's axes in the object frame, orthonormal): each triangle is clipped
// to the octant and coned from the corner, so the missing cap faces, which
// lie on planes through the corner, contribute nothing. Exact.
SolidMoments OctantMoments(const io::TriangleMesh& mesh, const Eigen::Matrix3d& frame,
                           const Vec3& corner_in_frame);

enum class RegionScheme {
  kAuto,    // kColors when the face colours split the mesh into closed parts, else kGrid
  kGrid,    // cells of a grid aligned with the solid's principal axes
  kColors,  // one region per face colour (each colour must bound a closed part)
  kSingle,  // one region: uniform density
};
const char* ToString(RegionScheme scheme);  // "auto", "grid", "colors", "single"
absl::StatusOr<RegionScheme> ParseRegionScheme(std::string_view text);

// Upper limit of RegionOptions::target_regions. The DENSITY fit's cost
// grows with the cube of the region count (its non-negative solves); at
// this many regions a fit on the box example takes 3-5 s (README, "Work limit").
inline constexpr int kMaxTargetRegions = 100;

struct RegionOptions {
  RegionScheme scheme = RegionScheme::kAuto;
  int target_regions = 12;  // kGrid: about this many non-empty cells (1..kMaxTargetRegions)
};

struct DensityRegion {
  std::string label;                       // "cell (2,0,1)", "colour #c0c0c0", "solid"
  SolidMoments moments;                    // unit density
  std::array<int, 3> cell = {-1, -1, -1};  // kGrid: cell index along the grid axes
  uint32_t color = 0;                      // kColors: 0xRRGGBB
};

struct RegionModel {
  RegionScheme scheme = RegionScheme::kSingle;  // resolved (never kAuto)
  std::vector<DensityRegion> regions;
  // Neighbouring regions (sharing a grid face), with a coupling weight
  // (dimensionless, ~1 for equal cells) used by the smoothness regulariser.
  std::vector<std::array<int, 2>> neighbours;
  std::vector<double> neighbour_weights;
  // kGrid: the grid frame (columns: the solid's principal axes in the
  // object frame, longest extent first), and the cell boundaries along each
  // axis in that frame (m, coordinates x_grid = grid_axes^T x_object).
  Eigen::Matrix3d grid_axes = Eigen::Matrix3d::Identity();
  std::array<std::vector<double>, 3> grid_planes;
  SolidMoments total;  // the whole solid
  // The region each mesh triangle belongs to (its centroid's cell for
  // kGrid, its colour for kColors, 0 for kSingle; -1 for a triangle in a
  // dropped, empty cell). Same size as mesh.triangles. For plots.
  std::vector<int> triangle_region;
  std::vector<std::string> notes;
};

// Splits the solid bounded by `mesh` (object frame, m; closed) into regions.
// Errors name `name`, e.g. "Pliers.ply: colour #e5e5e5 does not bound a
// closed part (423 boundary edges); use --regions grid".
// `interrupt` (may be empty) is polled while the grid's cells are
// integrated; when it returns true the result is absl::Cancelled("interrupted").
absl::StatusOr<RegionModel> BuildRegions(const io::TriangleMesh& mesh, const RegionOptions& options,
                                         std::string_view name = "mesh",
                                         const std::function<bool()>& interrupt = nullptr);

}  // namespace tactforce::inertia
