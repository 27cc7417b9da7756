// An SVG picture of a DENSITY fit: the mesh's silhouette in the three
// principal planes of the fitted inertia (views along the largest, middle
// and smallest principal axis), each triangle filled with the fitted density
// of its region, the fitted CoM (and the true one, when given) marked, and a
// colour bar in kg/m^3. For `tactforce inertia fit --plot FILE.svg`.
#pragma once

#include <optional>
#include <string>

#include "absl/status/statusor.h"
#include "tactforce/io/mesh.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

struct DensityPlotOptions {
  std::string title;             // drawn on top; empty: "<method> fit"
  std::optional<Vec3> true_com;  // object frame, m; drawn as a second marker
  std::string source;            // the input files, named under the title; empty: none
};

// The SVG document. `mesh` is the fitted mesh (object frame, m) and `fit`
// the result of FitInertia with it.
//
// Panels, in a row (or one under the other when that draws the mesh larger,
// as for a long tool): the planes of principal axes (1, 2), (1, 3) and
// (2, 3), i.e. views along axis 3, 2 and 1, where axis i is column i-1 of
// fit.principal_axes (moments ascending: axis 3 has the largest moment);
// coordinates in mm from the fitted CoM, one mm-per-pixel scale in all
// three. Triangles are filled by the density of their region
// (fit.region_model->triangle_region -> fit.densities) on a viridis-like
// ramp from 0 to a round number above the largest density (colour bar in
// kg/m^3); triangles of no region (-1) are light grey; the near side is
// drawn on top; edges between regions are outlined, so that regions of one
// density still show. A contradicted mesh (fit.mesh_contradicted) still has its
// region model: its densities are drawn, under a warning that they are the
// rejected fit's. Without a region model (a method other than DENSITY) the
// silhouette is drawn in grey with the CoM markers only.
//
// InvalidArgument when the mesh is empty or has out-of-range indices or
// non-finite vertices, when its triangle count differs from the fit's region
// model, or when the fit has not one density per region.
absl::StatusOr<std::string> DensityPlotSvg(const io::TriangleMesh& mesh, const InertiaFit& fit,
                                           const DensityPlotOptions& options = {});

}  // namespace tactforce::inertia
