// Solid moments of closed meshes (signed tetrahedra), octant clipping, and
// the regions of a DENSITY fit (principal-axis grid cells or colour parts).
#include "tactforce/inertia/density.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "internal.h"
#include "tactforce/io/enum_names.h"

namespace tactforce::inertia {
namespace {

using io::TriangleMesh;

// Adds the integrals of the signed tetrahedron (o, a, b, c).
void AddTetrahedron(const Vec3& o, const Vec3& a, const Vec3& b, const Vec3& c, SolidMoments* m) {
  const double v = (a - o).dot((b - o).cross(c - o)) / 6.0;
  if (v == 0.0) return;
  const Vec3 s = o + a + b + c;
  m->volume += v;
  m->first += v * 0.25 * s;
  // integral of x x^T over a tetrahedron = V/20 (sum_k p_k p_k^T + s s^T).
  m->second.noalias() += (v / 20.0) * (o * o.transpose() + a * a.transpose() + b * b.transpose() +
                                       c * c.transpose() + s * s.transpose());
}

// Sutherland-Hodgman clip of a convex polygon to {p(axis) <= limit}.
int ClipPolygon(const Vec3* in, int n, int axis, double limit, Vec3* out) {
  int k = 0;
  for (int i = 0; i < n; ++i) {
    const Vec3& p = in[i];
    const Vec3& q = in[(i + 1) % n];
    const bool pin = p(axis) <= limit, qin = q(axis) <= limit;
    if (pin) out[k++] = p;
    if (pin != qin) {
      const double t = (limit - p(axis)) / (q(axis) - p(axis));
      Vec3 x = p + t * (q - p);
      x(axis) = limit;  // exactly on the plane
      out[k++] = x;
    }
  }
  return k;
}

// Octant integrals in frame coordinates (vertices already in the frame).
SolidMoments OctantMomentsInFrame(const std::vector<Vec3>& v,
                                  const std::vector<std::array<int, 3>>& tris,
                                  const std::vector<Eigen::AlignedBox3d>& boxes,
                                  const Vec3& corner) {
  SolidMoments m;
  Vec3 buf_a[9], buf_b[9];
  for (size_t t = 0; t < tris.size(); ++t) {
    const Eigen::AlignedBox3d& box = boxes[t];
    if ((box.min().array() > corner.array()).any()) continue;  // entirely outside
    const Vec3& a = v[tris[t][0]];
    const Vec3& b = v[tris[t][1]];
    const Vec3& c = v[tris[t][2]];
    if ((box.max().array() <= corner.array()).all()) {
      AddTetrahedron(corner, a, b, c, &m);
      continue;
    }
    buf_a[0] = a, buf_a[1] = b, buf_a[2] = c;
    int n = 3;
    Vec3* in = buf_a;
    Vec3* out = buf_b;
    for (int axis = 0; axis < 3 && n > 0; ++axis) {
      if (box.max()(axis) <= corner(axis)) continue;
      n = ClipPolygon(in, n, axis, corner(axis), out);
      std::swap(in, out);
    }
    for (int i = 1; i + 1 < n; ++i) AddTetrahedron(corner, in[0], in[i], in[i + 1], &m);
  }
  return m;
}

SolidMoments Rotated(const SolidMoments& local, const Eigen::Matrix3d& frame) {
  SolidMoments m;
  m.volume = local.volume;
  m.first = frame * local.first;
  m.second = frame * local.second * frame.transpose();
  return m;
}

std::string ColorName(uint32_t c) { return absl::StrFormat("colour #%06x", c & 0xffffff); }

// Boundary edges of a subset of triangles (edges whose reverse is missing).
int BoundaryEdges(const io::TriangleMesh& mesh, const std::vector<int>& tris) {
  std::unordered_map<uint64_t, int> directed;
  directed.reserve(tris.size() * 3);
  auto key = [](int a, int b) {
    return (static_cast<uint64_t>(static_cast<uint32_t>(a)) << 32) | static_cast<uint32_t>(b);
  };
  for (int t : tris)
    for (int k = 0; k < 3; ++k)
      ++directed[key(mesh.triangles[t][k], mesh.triangles[t][(k + 1) % 3])];
  int boundary = 0;
  for (const auto& [e, count] : directed) {
    const int a = static_cast<int>(e >> 32), b = static_cast<int>(e & 0xffffffffu);
    auto it = directed.find(key(b, a));
    if (it == directed.end() || it->second != count) ++boundary;
  }
  return boundary;
}

absl::StatusOr<RegionModel> ColorRegions(const io::TriangleMesh& mesh, std::string_view name) {
  if (mesh.face_colors.size() != mesh.triangles.size())
    return absl::InvalidArgumentError(
        absl::StrCat(std::string(name), ": the mesh has no face colours (use --regions grid)"));
  std::map<uint32_t, std::vector<int>> groups;
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    groups[mesh.face_colors[t] & 0xffffff].push_back(static_cast<int>(t));
  RegionModel model;
  model.scheme = RegionScheme::kColors;
  model.triangle_region.assign(mesh.triangles.size(), -1);
  for (const auto& [color, tris] : groups) {
    const int boundary = BoundaryEdges(mesh, tris);
    if (boundary > 0)
      return absl::InvalidArgumentError(absl::StrCat(std::string(name), ": ", ColorName(color),
                                                     " does not bound a closed part (", boundary,
                                                     " boundary edges); use --regions grid"));
    io::TriangleMesh part;
    part.vertices = mesh.vertices;
    for (int t : tris) part.triangles.push_back(mesh.triangles[t]);
    DensityRegion r;
    r.label = ColorName(color);
    r.color = color;
    r.moments = MeshMoments(part);
    if (!(r.moments.volume > 0))
      return absl::InvalidArgumentError(absl::StrCat(std::string(name), ": ", ColorName(color),
                                                     " encloses volume ", r.moments.volume,
                                                     " m^3 (must be > 0)"));
    for (int t : tris) model.triangle_region[t] = static_cast<int>(model.regions.size());
    model.regions.push_back(r);
  }
  // Parts of a CAD assembly touch in unknown ways: every pair is a neighbour.
  for (size_t i = 0; i < model.regions.size(); ++i)
    for (size_t j = i + 1; j < model.regions.size(); ++j) {
      model.neighbours.push_back({static_cast<int>(i), static_cast<int>(j)});
      model.neighbour_weights.push_back(1.0);
    }
  model.notes.push_back(
      absl::StrCat(model.regions.size(), " regions: one per face colour (closed parts)"));
  return model;
}

// Principal axes of the uniform solid about its centroid, columns sorted by
// the vertices' extent along them (longest first), right-handed.
Eigen::Matrix3d GridAxes(const io::TriangleMesh& mesh, const SolidMoments& total) {
  const Vec3 c = total.Centroid();
  const Eigen::Matrix3d cov = total.second / total.volume - c * c.transpose();
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(0.5 * (cov + cov.transpose()));
  Eigen::Matrix3d axes = es.eigenvectors();
  Vec3 extent;
  for (int a = 0; a < 3; ++a) {
    double lo = HUGE_VAL, hi = -HUGE_VAL;
    for (const Vec3& v : mesh.vertices) {
      const double x = axes.col(a).dot(v);
      lo = std::min(lo, x), hi = std::max(hi, x);
    }
    extent(a) = hi - lo;
  }
  std::array<int, 3> order = {0, 1, 2};
  std::sort(order.begin(), order.end(), [&](int i, int j) { return extent(i) > extent(j); });
  Eigen::Matrix3d sorted;
  for (int a = 0; a < 3; ++a) sorted.col(a) = axes.col(order[a]);
  if (sorted.determinant() < 0) sorted.col(2) = -sorted.col(2);
  return sorted;
}

// Cell counts along the grid axes for cells of edge about h.
std::array<int, 3> CellCounts(const Vec3& extent, double h) {
  std::array<int, 3> n;
  for (int a = 0; a < 3; ++a) n[a] = std::max(1, static_cast<int>(std::ceil(extent(a) / h - 1e-9)));
  return n;
}

// Moments of the grid cell whose upper corner is (i, j, k), by inclusion and
// exclusion of the octant integrals at its 8 corners.
template <class OctantIndex>
SolidMoments CellFromOctants(const std::vector<SolidMoments>& octant, const OctantIndex& idx, int i,
                             int j, int k) {
  SolidMoments cell;
  for (int d = 0; d < 8; ++d) {
    const int di = d & 1, dj = (d >> 1) & 1, dk = (d >> 2) & 1;
    const SolidMoments& o = octant[idx(i - di, j - dj, k - dk)];
    if ((di + dj + dk) % 2 == 0)
      cell += o;
    else
      cell -= o;
  }
  return cell;
}

// Incomplete when `poll` fires (the caller checks poll->stopped()).
RegionModel GridRegions(const io::TriangleMesh& mesh, const SolidMoments& total,
                        const std::array<int, 3>& n, const Eigen::Matrix3d& axes, const Vec3& lo,
                        const Vec3& hi, const std::vector<Vec3>& v,
                        const std::vector<Eigen::AlignedBox3d>& boxes,
                        internal::InterruptPoll* poll) {
  RegionModel model;
  model.scheme = RegionScheme::kGrid;
  model.grid_axes = axes;
  for (int a = 0; a < 3; ++a) {
    model.grid_planes[a].resize(n[a] + 1);
    for (int i = 0; i <= n[a]; ++i) model.grid_planes[a][i] = lo(a) + (hi(a) - lo(a)) * i / n[a];
    // The outer planes enclose the mesh exactly (no clipping at them).
    model.grid_planes[a][0] = lo(a);
    model.grid_planes[a][n[a]] = hi(a);
  }
  // Octant integrals O(i, j, k) for upper corners i = 1..n (index 0: empty).
  auto idx = [&](int i, int j, int k) { return (i * (n[1] + 1) + j) * (n[2] + 1) + k; };
  std::vector<SolidMoments> octant((n[0] + 1) * (n[1] + 1) * (n[2] + 1));
  for (int i = 1; i <= n[0]; ++i)
    for (int j = 1; j <= n[1]; ++j)
      for (int k = 1; k <= n[2]; ++k) {
        if (poll->Tick(1 + static_cast<int64_t>(mesh.triangles.size()) / 16)) return model;
        const Vec3 corner(model.grid_planes[0][i], model.grid_planes[1][j],
                          model.grid_planes[2][k]);
        octant[idx(i, j, k)] = OctantMomentsInFrame(v, mesh.triangles, boxes, corner);
      }
  // Cells by inclusion-exclusion; empty cells are dropped.
  std::vector<int> region_of((n[0]) * (n[1]) * (n[2]), -1);
  const double min_volume = 1e-9 * total.volume;
  for (int i = 1; i <= n[0]; ++i)
    for (int j = 1; j <= n[1]; ++j)
      for (int k = 1; k <= n[2]; ++k) {
        const SolidMoments cell = CellFromOctants(octant, idx, i, j, k);
        if (!(cell.volume > min_volume)) continue;
        DensityRegion r;
        r.cell = {i - 1, j - 1, k - 1};
        r.label = absl::StrFormat("cell (%d,%d,%d)", i - 1, j - 1, k - 1);
        r.moments = Rotated(cell, axes);
        region_of[((i - 1) * n[1] + (j - 1)) * n[2] + (k - 1)] =
            static_cast<int>(model.regions.size());
        model.regions.push_back(r);
      }
  auto region_at = [&](int i, int j, int k) {
    if (i < 0 || j < 0 || k < 0 || i >= n[0] || j >= n[1] || k >= n[2]) return -1;
    return region_of[(i * n[1] + j) * n[2] + k];
  };
  for (size_t r = 0; r < model.regions.size(); ++r) {
    const auto& c = model.regions[r].cell;
    for (int a = 0; a < 3; ++a) {
      std::array<int, 3> d = c;
      ++d[a];
      const int s = region_at(d[0], d[1], d[2]);
      if (s < 0) continue;
      model.neighbours.push_back({static_cast<int>(r), s});
      model.neighbour_weights.push_back(1.0);
    }
  }
  // Region of each triangle: the cell of its centroid.
  model.triangle_region.resize(mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const Vec3 c =
        (v[mesh.triangles[t][0]] + v[mesh.triangles[t][1]] + v[mesh.triangles[t][2]]) / 3.0;
    std::array<int, 3> cell;
    for (int a = 0; a < 3; ++a) {
      const auto& p = model.grid_planes[a];
      cell[a] =
          std::clamp(static_cast<int>(std::upper_bound(p.begin(), p.end(), c(a)) - p.begin()) - 1,
                     0, n[a] - 1);
    }
    model.triangle_region[t] = region_at(cell[0], cell[1], cell[2]);
  }
  model.notes.push_back(
      absl::StrFormat("%d regions: non-empty cells of a %dx%dx%d grid on the principal axes",
                      static_cast<int>(model.regions.size()), n[0], n[1], n[2]));
  return model;
}

}  // namespace

Vector10d SolidMoments::Standard(double density) const {
  Vector10d pi;
  const Eigen::Matrix3d io = second.trace() * Eigen::Matrix3d::Identity() - second;
  pi << volume, first, io(0, 0), io(1, 1), io(2, 2), io(0, 1), io(0, 2), io(1, 2);
  return density * pi;
}

SolidMoments& SolidMoments::operator+=(const SolidMoments& o) {
  volume += o.volume;
  first += o.first;
  second += o.second;
  return *this;
}

SolidMoments& SolidMoments::operator-=(const SolidMoments& o) {
  volume -= o.volume;
  first -= o.first;
  second -= o.second;
  return *this;
}

SolidMoments MeshMoments(const io::TriangleMesh& mesh) {
  SolidMoments m;
  if (mesh.vertices.empty()) return m;
  // Cone from a vertex of the mesh: smaller terms than from the origin.
  const Vec3 o = mesh.vertices[0];
  for (const auto& t : mesh.triangles)
    AddTetrahedron(o, mesh.vertices[t[0]], mesh.vertices[t[1]], mesh.vertices[t[2]], &m);
  return m;
}

SolidMoments OctantMoments(const io::TriangleMesh& mesh, const Eigen::Matrix3d& frame,
                           const Vec3& corner) {
  std::vector<Vec3> v(mesh.vertices.size());
  for (size_t i = 0; i < v.size(); ++i) v[i] = frame.transpose() * mesh.vertices[i];
  std::vector<Eigen::AlignedBox3d> boxes(mesh.triangles.size());
  for (size_t t = 0; t < boxes.size(); ++t) {
    boxes[t] = Eigen::AlignedBox3d(v[mesh.triangles[t][0]]);
    boxes[t].extend(v[mesh.triangles[t][1]]).extend(v[mesh.triangles[t][2]]);
  }
  return Rotated(OctantMomentsInFrame(v, mesh.triangles, boxes, corner), frame);
}

namespace {

// Enum names (io/enum_names.h); "", "unspecified", "colours" and "uniform" are aliases.
constexpr io::EnumNameRow<RegionScheme> kSchemeNames[] = {
    {RegionScheme::kAuto, "auto"},
    {RegionScheme::kGrid, "grid"},
    {RegionScheme::kColors, "colors"},
    {RegionScheme::kSingle, "single"},
    {RegionScheme::kAuto, "", "", false},
    {RegionScheme::kAuto, "unspecified", "", false},
    {RegionScheme::kColors, "colours", "", false},
    {RegionScheme::kSingle, "uniform", "", false}};

}  // namespace

const char* ToString(RegionScheme s) { return io::EnumName(kSchemeNames, s); }

absl::StatusOr<RegionScheme> ParseRegionScheme(std::string_view text) {
  return io::ParseEnumName(kSchemeNames, text, "regions", "region-scheme-");
}

absl::StatusOr<RegionModel> BuildRegions(const io::TriangleMesh& mesh, const RegionOptions& options,
                                         std::string_view name,
                                         const std::function<bool()>& interrupt) {
  if (options.target_regions < 1 || options.target_regions > kMaxTargetRegions)
    return absl::InvalidArgumentError(absl::StrCat("target_regions: must be in 1..",
                                                   kMaxTargetRegions, " (got ",
                                                   options.target_regions, ")"));
  if (mesh.triangles.empty())
    return absl::InvalidArgumentError(absl::StrCat(std::string(name), ": no triangles"));
  const SolidMoments total = MeshMoments(mesh);
  if (!(total.volume > 0))
    return absl::InvalidArgumentError(
        absl::StrCat(std::string(name), ": volume ", total.volume,
                     " m^3 is not positive: the mesh is inside out (flip the winding)"));
  RegionScheme scheme = options.scheme;
  absl::StatusOr<RegionModel> colors = absl::UnknownError("");
  if (scheme == RegionScheme::kAuto || scheme == RegionScheme::kColors) {
    colors = ColorRegions(mesh, name);
    if (scheme == RegionScheme::kColors && !colors.ok()) return colors.status();
    if (colors.ok() && colors->regions.size() >= 2) {
      colors->total = total;
      return colors;
    }
    scheme = RegionScheme::kGrid;
  }
  if (scheme == RegionScheme::kSingle || options.target_regions == 1) {
    RegionModel model;
    model.scheme = RegionScheme::kSingle;
    DensityRegion r;
    r.label = "solid";
    r.moments = total;
    model.regions.push_back(r);
    model.triangle_region.assign(mesh.triangles.size(), 0);
    model.total = total;
    model.notes.push_back("1 region: uniform density");
    return model;
  }
  // Grid on the principal axes; the resolution is refined until about
  // target_regions cells are non-empty (thin or hollow shapes leave many
  // cells empty).
  const Eigen::Matrix3d axes = GridAxes(mesh, total);
  std::vector<Vec3> v(mesh.vertices.size());
  Vec3 lo = Vec3::Constant(HUGE_VAL), hi = Vec3::Constant(-HUGE_VAL);
  for (size_t i = 0; i < v.size(); ++i) {
    v[i] = axes.transpose() * mesh.vertices[i];
    lo = lo.cwiseMin(v[i]);
    hi = hi.cwiseMax(v[i]);
  }
  std::vector<Eigen::AlignedBox3d> boxes(mesh.triangles.size());
  for (size_t t = 0; t < boxes.size(); ++t) {
    boxes[t] = Eigen::AlignedBox3d(v[mesh.triangles[t][0]]);
    boxes[t].extend(v[mesh.triangles[t][1]]).extend(v[mesh.triangles[t][2]]);
  }
  const Vec3 extent = hi - lo;
  // Largest cell edge h with at most target_regions cells in the box.
  double h = extent(0);
  for (int d = 1; d <= 4 * options.target_regions; ++d) {
    const double cand = extent(0) / d;
    const auto n = CellCounts(extent, cand);
    if (static_cast<long>(n[0]) * n[1] * n[2] > options.target_regions) break;
    h = cand;
  }
  internal::InterruptPoll poll(interrupt);
  RegionModel model;
  for (int attempt = 0; attempt < 4; ++attempt) {
    if (poll.Check()) return internal::Interrupted();
    model = GridRegions(mesh, total, CellCounts(extent, h), axes, lo, hi, v, boxes, &poll);
    if (poll.stopped()) return internal::Interrupted();
    if (static_cast<int>(model.regions.size()) * 10 >= 7 * options.target_regions) break;
    // Too many empty cells: refine so the non-empty count approaches the target.
    const double ratio =
        static_cast<double>(options.target_regions) / std::max<size_t>(model.regions.size(), 1);
    h /= std::min(2.0, std::max(1.15, std::cbrt(ratio)));
  }
  model.total = total;
  return model;
}

}  // namespace tactforce::inertia
