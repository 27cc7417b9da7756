// The SVG picture of a DENSITY fit (density_plot.h): what to draw is decided
// here (the three principal views, colours by fitted density, CoM markers,
// the layout at one scale), how to draw it is io/svg.h's (canvas, axes and
// ticks, markers, legend, colour bar).
//
// Size: the projected vertices snap to a grid of kGrid px and are written as
// integers in a scale(kGrid) group, with relative path commands. Snapping is
// vertex clustering: a triangle smaller than the grid collapses and is
// dropped, while its neighbours, which share its snapped corners, close over
// it, so no holes open (unlike skipping small triangles, which leaves holes
// wherever a fine tessellation has many of them: a CAD mesh of 100k faces is
// mostly sub-pixel triangles here). Back faces of a closed, outward-oriented
// mesh are culled; consecutive triangles of one colour share a <path>; and
// each colour is a CSS class.
#include "tactforce/inertia/density_plot.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <numeric>
#include <unordered_map>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/svg.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::inertia {
namespace {

using io::TriangleMesh;

constexpr uint32_t kGrey = 0xd0d0d0;  // no region / no region model
constexpr double kMaxPanelsWidth =
    960;  // px, the three panels together (in a row), or the widest (in a column)
constexpr double kMaxPanelHeight = 420;   // px, the tallest (in a row)
constexpr double kMaxColumnHeight = 640;  // px, the three panels' drawings together (in a column)
constexpr double kMinPanelSize = 90;      // px, so that ticks and labels fit
constexpr double kPad = 10;               // px between the mesh and a panel's frame
constexpr double kGrid = 0.5;        // px: vertices snap to this grid (integer path coordinates)
constexpr double kSeamStroke = 0.5;  // px, same colour as the fill: hides anti-aliasing seams
constexpr double kBarHeight = 180;   // px, the colour bar
constexpr double kLeft = 64, kGap = 64, kRowGap = 84, kBottom = 56,
                 kColumn = 240;  // px, page layout

// One view: the plane of principal axes `h` (right) and `v` (up), seen from
// the side of h x v.
struct View {
  int h, v, k;        // k: the axis looked along
  double depth_sign;  // depth = depth_sign * coordinate k (larger: nearer)
};
constexpr std::array<View, 3> kViews = {{{0, 1, 2, +1.0}, {0, 2, 1, -1.0}, {1, 2, 0, +1.0}}};
const char* const kMomentName[3] = {"smallest", "middle", "largest"};

struct Marker {
  Vec3 p;  // principal frame, m
  bool fitted;
};

// Two shapes of two sizes, so that coincident markers both show: a small
// cross inside a large diamond.
const io::MarkerStyle kFittedCom{.shape = io::MarkerShape::kCross,
                                 .color = "black",
                                 .size = 12,
                                 .halo = true,
                                 .css_class = "fitted-com"};
const io::MarkerStyle kTrueCom{.shape = io::MarkerShape::kDiamond,
                               .color = "#e4007c",
                               .size = 22,
                               .line_width = 2,
                               .halo = true,
                               .css_class = "true-com"};

absl::Status CheckInputs(const TriangleMesh& mesh, const InertiaFit& fit) {
  if (mesh.vertices.empty() || mesh.triangles.empty())
    return absl::InvalidArgumentError("density plot: the mesh is empty");
  const int nv = static_cast<int>(mesh.vertices.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int i : mesh.triangles[t])
      if (i < 0 || i >= nv)
        return absl::InvalidArgumentError(absl::StrCat("density plot: mesh.triangles[", t,
                                                       "]: vertex index ", i, " out of range (", nv,
                                                       " vertices)"));
  for (int i = 0; i < nv; ++i)
    if (!mesh.vertices[i].allFinite())
      return absl::InvalidArgumentError(
          absl::StrCat("density plot: mesh.vertices[", i, "]: not finite"));
  const RegionModel* model = fit.region_model.get();
  if (model == nullptr) return absl::OkStatus();
  if (model->triangle_region.size() != mesh.triangles.size())
    return absl::InvalidArgumentError(
        absl::StrCat("density plot: the mesh has ", mesh.triangles.size(),
                     " triangles but the fit's region model has ", model->triangle_region.size(),
                     " (not the mesh that was fitted)"));
  if (fit.densities.size() != model->regions.size())
    return absl::InvalidArgumentError(absl::StrCat("density plot: the fit has ",
                                                   fit.densities.size(), " densities for ",
                                                   model->regions.size(), " regions"));
  return absl::OkStatus();
}

// The mesh and the CoM markers in the fitted principal frame, from the fitted CoM.
struct PrincipalGeometry {
  std::vector<Vec3> p;  // vertices, m
  std::vector<Marker> markers;
  Vec3 lo, hi;  // bounding box of both (no axis flatter than 1e-6 of the largest)
};

PrincipalGeometry InPrincipalFrame(const TriangleMesh& mesh, const InertiaFit& fit,
                                   const DensityPlotOptions& options) {
  Eigen::Matrix3d axes = fit.principal_axes;
  if (!axes.allFinite() || std::abs(axes.determinant()) < 0.5) axes = Eigen::Matrix3d::Identity();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);  // right-handed, for the back-face test
  const bool com_finite = fit.params.com.allFinite();
  const Vec3 origin = com_finite ? fit.params.com : Vec3::Zero();
  PrincipalGeometry g;
  g.p.reserve(mesh.vertices.size());
  for (const Vec3& v : mesh.vertices) g.p.push_back(axes.transpose() * (v - origin));
  if (com_finite) g.markers.push_back({Vec3::Zero(), true});
  if (options.true_com && options.true_com->allFinite())
    g.markers.push_back({axes.transpose() * (*options.true_com - origin), false});
  g.lo = g.hi = g.p[0];
  for (const Vec3& q : g.p) g.lo = g.lo.cwiseMin(q), g.hi = g.hi.cwiseMax(q);
  for (const Marker& m : g.markers) g.lo = g.lo.cwiseMin(m.p), g.hi = g.hi.cwiseMax(m.p);
  const double size = std::max((g.hi - g.lo).maxCoeff(), 1e-9);
  for (int a = 0; a < 3; ++a)
    if (g.hi(a) - g.lo(a) < 1e-6 * size)
      g.lo(a) -= 0.5e-6 * size, g.hi(a) += 0.5e-6 * size;  // a flat mesh
  return g;
}

// Where everything goes: one scale (px per m) for all three views, each view
// a frame in mm from the fitted CoM; the views in a row (all of the tallest
// view's height) or in a column (all of the widest view's width), whichever
// draws the mesh larger. Frames start at y = 0; DensityPlotSvg moves them
// under the header.
struct Layout {
  double scale = 1;  // px per m
  bool column = false;
  std::array<io::PlotFrame, 3> frames;  // data in mm
  std::array<std::string, 3> titles;
  double column_x = 0;           // legend and colour bar
  double width = 0, bottom = 0;  // px; bottom: below the last frame's axis titles
};

double ChooseScale(const Vec3& extent, bool column) {
  double along = 0,
         across = 0;  // m: the sum of the views' sizes along the layout, and the largest across it
  for (const View& v : kViews) {
    along += column ? extent(v.v) : extent(v.h);
    across = std::max(across, column ? extent(v.h) : extent(v.v));
  }
  return column ? std::min(kMaxPanelsWidth / across, kMaxColumnHeight / along)
                : std::min(kMaxPanelsWidth / along, kMaxPanelHeight / across);
}

Layout PlaceViews(const PrincipalGeometry& g) {
  const Vec3 extent = g.hi - g.lo;
  Layout l;
  const double row_scale = ChooseScale(extent, false), column_scale = ChooseScale(extent, true);
  l.column = column_scale >
             1.2 * row_scale;  // a column only when clearly larger (a row reads more easily)
  l.scale = l.column ? column_scale : row_scale;
  // Half-sizes in m: at least kMinPanelSize px, plus kPad px around the mesh.
  auto half = [&](int a) {
    return 0.5 * std::max(extent(a), (kMinPanelSize - 2 * kPad) / l.scale) + kPad / l.scale;
  };
  double half_height = 0;
  for (const View& v : kViews) half_height = std::max(half_height, half(v.v));
  double x = kLeft, y = 0, right = 0;
  for (int i = 0; i < 3; ++i) {
    const View& v = kViews[i];
    const double mid_h = 0.5 * (g.lo(v.h) + g.hi(v.h)), mid_v = 0.5 * (g.lo(v.v) + g.hi(v.v));
    const double hw = half(v.h), hh = l.column ? half(v.v) : half_height;
    io::PlotFrame& f = l.frames[i];
    f.x_lo = 1000 * (mid_h - hw), f.x_hi = 1000 * (mid_h + hw);
    f.y_lo = 1000 * (mid_v - hh), f.y_hi = 1000 * (mid_v + hh);
    f.left = x, f.top = y, f.width = 2 * hw * l.scale, f.height = 2 * hh * l.scale;
    l.titles[i] = absl::StrFormat("along axis %d (%s moment)", v.k + 1, kMomentName[v.k]);
    // A narrow panel still leaves room for its title (bold 12 px).
    const double w = std::max(f.width, io::TextWidth(l.titles[i], 12) * 1.1);
    right = std::max(right, x + w);
    if (l.column)
      y += f.height + kRowGap;
    else
      x += w + kGap;
  }
  l.column_x = right + 40;
  l.width = std::ceil(l.column_x + kColumn);
  l.bottom = l.column ? y - kRowGap + kBottom : l.frames[0].height + kBottom;
  return l;
}

// Colours: per triangle (its region's density on the ramp, grey without a
// region), and the colour bar's range: 0 to a round number at or above the
// largest density (0 to 1000 when every density is 0).
struct DensityColors {
  std::vector<uint32_t> triangle;
  io::Ticks bar_ticks;
  double bar_top = 1000;
};

DensityColors ColorByDensity(const TriangleMesh& mesh, const InertiaFit& fit,
                             const io::ColorRamp& ramp) {
  DensityColors c;
  c.triangle.assign(mesh.triangles.size(), kGrey);
  const RegionModel* model = fit.region_model.get();
  if (model == nullptr) return c;
  double max_density = 0;
  for (const InertiaFit::RegionDensity& d : fit.densities)
    if (std::isfinite(d.density)) max_density = std::max(max_density, d.density);
  const double bar_max = max_density > 0 ? max_density : 1000.0;
  const double step = io::NiceStep(bar_max / 5);
  c.bar_top = std::ceil(bar_max / step * (1 - 1e-12)) * step;
  c.bar_ticks = io::TicksAt(0, c.bar_top, step);
  std::vector<uint32_t> region_color;
  for (const InertiaFit::RegionDensity& d : fit.densities)
    region_color.push_back(std::isfinite(d.density) ? ramp.At(d.density / c.bar_top) : kGrey);
  for (size_t t = 0; t < mesh.triangles.size(); ++t) {
    const int r = model->triangle_region[t];
    if (r >= 0 && r < static_cast<int>(region_color.size())) c.triangle[t] = region_color[r];
  }
  return c;
}

// One CSS class per colour ("c0", "c1", ...): the <style> element, and each
// triangle's class index.
std::string ColorClasses(const std::vector<uint32_t>& color, std::vector<int>* color_class) {
  std::vector<uint32_t> palette(color.begin(), color.end());
  std::sort(palette.begin(), palette.end());
  palette.erase(std::unique(palette.begin(), palette.end()), palette.end());
  color_class->resize(color.size());
  for (size_t t = 0; t < color.size(); ++t)
    (*color_class)[t] = static_cast<int>(
        std::lower_bound(palette.begin(), palette.end(), color[t]) - palette.begin());
  std::string style = absl::StrFormat("<style>.mesh path{stroke-width:%gpx;stroke-linejoin:round}",
                                      kSeamStroke / kGrid);
  for (size_t i = 0; i < palette.size(); ++i)
    absl::StrAppend(&style, ".c", i, "{fill:", io::HexColor(palette[i]),
                    ";stroke:", io::HexColor(palette[i]), "}");
  return absl::StrCat(style, "</style>\n");
}

// Appends an integer to a path; a leading space unless the number is
// negative (its sign separates it) or it follows a command letter.
void AppendCoordinate(std::string* d, long v, bool after_command) {
  if (!after_command && v >= 0) d->push_back(' ');
  absl::StrAppend(d, v);
}

// What the mesh paths of one view need.
struct MeshPaint {
  const TriangleMesh& mesh;
  const std::vector<Vec3>& p;  // principal frame, m
  const std::vector<int>& color_class;
  bool cull = false;  // hide back faces
};

// A mesh edge (vertex indices a, b) and its triangles t1 and t2 (-1: an
// open edge); `region_change` when they are of different regions.
struct RegionEdge {
  int a, b, t1, t2;
  bool region_change;
};

// Per vertex, the first vertex at the same position: a mesh read as
// separate triangles (no shared vertices) still has its edges matched.
std::vector<int> WeldedIndices(const TriangleMesh& mesh) {
  struct Hash {
    size_t operator()(const std::array<double, 3>& p) const {
      return std::hash<double>()(p[0]) ^ (std::hash<double>()(p[1]) * 31) ^
             (std::hash<double>()(p[2]) * 961);
    }
  };
  std::unordered_map<std::array<double, 3>, int, Hash> seen;
  std::vector<int> welded(mesh.vertices.size());
  for (size_t i = 0; i < mesh.vertices.size(); ++i)
    welded[i] = seen.emplace(std::array<double, 3>{mesh.vertices[i].x(), mesh.vertices[i].y(),
                                                   mesh.vertices[i].z()},
                             static_cast<int>(i))
                    .first->second;
  return welded;
}

// Every edge of the mesh with its triangles (none without a region model):
// outlines are region changes and, per view, the contours of each part; an
// edge shared by more than two triangles is taken for its first two.
std::vector<RegionEdge> RegionBoundaries(const TriangleMesh& mesh, const RegionModel* model) {
  std::vector<RegionEdge> out;
  if (model == nullptr) return out;
  const std::vector<int> welded = WeldedIndices(mesh);
  std::unordered_map<uint64_t, int> first;  // edge key -> the first triangle seen with it
  first.reserve(3 * mesh.triangles.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const int a = std::min(welded[mesh.triangles[t][k]], welded[mesh.triangles[t][(k + 1) % 3]]);
      const int b = std::max(welded[mesh.triangles[t][k]], welded[mesh.triangles[t][(k + 1) % 3]]);
      const uint64_t key = (static_cast<uint64_t>(a) << 32) | static_cast<uint32_t>(b);
      const auto [it, inserted] = first.emplace(key, static_cast<int>(out.size()));
      if (inserted) {
        out.push_back({a, b, static_cast<int>(t), -1, false});
      } else if (RegionEdge& e = out[it->second]; e.t2 < 0) {
        e.t2 = static_cast<int>(t);
        e.region_change = model->triangle_region[e.t1] != model->triangle_region[t];
      }
    }
  return out;
}

// Twice the signed area of triangle t seen in `view` (positive: facing us).
double FacingArea(const MeshPaint& paint, const View& view, const io::PlotFrame& frame, int t) {
  std::array<double, 6> e;
  for (int k = 0; k < 3; ++k) {
    const Vec3& q = paint.p[paint.mesh.triangles[t][k]];
    e[2 * k] = frame.X(1000 * q(view.h)), e[2 * k + 1] = frame.Y(1000 * q(view.v));
  }
  return -((e[2] - e[0]) * (e[5] - e[1]) - (e[4] - e[0]) * (e[3] - e[1]));
}

// The outlines seen in `view` as one thin dark path over the mesh: region
// changes (on a culled mesh, those with a triangle facing us), contours
// (one triangle facing us, the other not: the outline of each part, also of
// parts that are separate shells) and open edges.
std::string RegionOutlines(const MeshPaint& paint, const std::vector<RegionEdge>& edges,
                           const View& view, const io::PlotFrame& frame) {
  std::string d;
  for (const RegionEdge& e : edges) {
    const bool front1 = FacingArea(paint, view, frame, e.t1) > 0;
    const bool front2 = e.t2 >= 0 && FacingArea(paint, view, frame, e.t2) > 0;
    const bool contour = e.t2 < 0 || front1 != front2;
    if (!(e.region_change || contour) || (paint.cull && !front1 && !front2)) continue;
    const Vec3 &p = paint.p[e.a], &q = paint.p[e.b];
    // Snapped to kGrid like the mesh; a segment of no length there is seen end on.
    const long x1 = std::lround(frame.X(1000 * p(view.h)) / kGrid),
               y1 = std::lround(frame.Y(1000 * p(view.v)) / kGrid);
    const long x2 = std::lround(frame.X(1000 * q(view.h)) / kGrid),
               y2 = std::lround(frame.Y(1000 * q(view.v)) / kGrid);
    if (x1 == x2 && y1 == y2) continue;
    d.push_back('M');
    AppendCoordinate(&d, x1, true);
    AppendCoordinate(&d, y1, false);
    d.push_back('l');
    AppendCoordinate(&d, x2 - x1, true);
    AppendCoordinate(&d, y2 - y1, false);
  }
  if (d.empty()) return "";
  return absl::StrFormat(
      "<path class=\"region-outline\" transform=\"scale(%g)\" d=\"%s\" fill=\"none\" "
      "stroke=\"#202020\" "
      "stroke-width=\"%g\" stroke-opacity=\"0.8\"/>\n",
      kGrid, d, 0.8 / kGrid);
}

// Twice the signed area of a projected triangle (x0 y0 x1 y1 x2 y2),
// positive when counter-clockwise on the page (y down), i.e. facing us.
template <typename Corners>
double FacingArea2(const Corners& q) {
  return -(static_cast<double>(q[2] - q[0]) * (q[5] - q[1]) -
           static_cast<double>(q[4] - q[0]) * (q[3] - q[1]));
}

// The mesh in view `view` through `frame`, far to near, snapped to kGrid px,
// in a scale(kGrid) group: one <path class="cN"> per run of one colour.
std::string MeshPaths(const MeshPaint& paint, const View& view, const io::PlotFrame& frame) {
  const size_t n = paint.mesh.triangles.size();
  std::vector<double> depth(n);
  for (size_t t = 0; t < n; ++t) {
    const auto& tri = paint.mesh.triangles[t];
    depth[t] = view.depth_sign *
               (paint.p[tri[0]](view.k) + paint.p[tri[1]](view.k) + paint.p[tri[2]](view.k));
  }
  std::vector<int> order(n);
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return depth[a] < depth[b]; });
  std::string out = absl::StrFormat("<g class=\"mesh\" transform=\"scale(%g)\">\n", kGrid), d;
  int current = -1;
  auto flush = [&] {
    if (current >= 0) absl::StrAppend(&out, "<path class=\"c", current, "\" d=\"", d, "\"/>\n");
    d.clear();
  };
  for (int t : order) {
    std::array<double, 6> e;  // px
    std::array<long, 6> c;    // grid units
    for (int k = 0; k < 3; ++k) {
      const Vec3& q = paint.p[paint.mesh.triangles[t][k]];
      e[2 * k] = frame.X(1000 * q(view.h));
      e[2 * k + 1] = frame.Y(1000 * q(view.v));
      c[2 * k] = std::lround(e[2 * k] / kGrid);
      c[2 * k + 1] = std::lround(e[2 * k + 1] / kGrid);
    }
    // Facing is decided on the exact projection; a snapped triangle of no area covers nothing.
    if ((paint.cull && !(FacingArea2(e) > 0)) || FacingArea2(c) == 0) continue;
    if (paint.color_class[t] != current) {
      flush();
      current = paint.color_class[t];
    }
    d.push_back('M');
    AppendCoordinate(&d, c[0], true);
    AppendCoordinate(&d, c[1], false);
    d.push_back('l');
    AppendCoordinate(&d, c[2] - c[0], true);
    AppendCoordinate(&d, c[3] - c[1], false);
    AppendCoordinate(&d, c[4] - c[2], false);
    AppendCoordinate(&d, c[5] - c[3], false);
    d.push_back('z');
  }
  flush();
  return absl::StrCat(out, "</g>\n");
}

// View i: title, grid and ticks in mm, the mesh, the frame, the CoM markers.
void DrawView(io::SvgCanvas& canvas, int i, const Layout& layout, const MeshPaint& paint,
              const std::vector<RegionEdge>& edges, const std::vector<Marker>& markers) {
  const View& v = kViews[i];
  const io::PlotFrame& f = layout.frames[i];
  canvas.OpenGroup(absl::StrCat("id=\"view-", i + 1, "\""));
  canvas.Text(f.left, f.top - 8, layout.titles[i], {.bold = true});
  // Ticks about every 80 px, but at least three on an axis (finer on short ones).
  auto ticks = [&](double lo, double hi, double px) {
    return io::AxisTicks(lo, hi, std::max(2, int(px / 80)));
  };
  const io::AxisStyle x_axis{.title = absl::StrFormat("axis %d (mm)", v.h + 1),
                             .tick_font_size = 11};
  const io::AxisStyle y_axis{
      .title = absl::StrFormat("axis %d (mm)", v.v + 1), .title_offset = 40, .tick_font_size = 11};
  io::DrawAxes(canvas, f, ticks(f.x_lo, f.x_hi, f.width), x_axis, ticks(f.y_lo, f.y_hi, f.height),
               y_axis);
  canvas.Raw(MeshPaths(paint, v, f));
  canvas.Raw(RegionOutlines(paint, edges, v, f));
  io::DrawFrameOutline(canvas, f, io::Stroke{"#888", 1, ""}, "frame");
  // CoM markers on top: the true one first, so that the fitted cross stays visible.
  for (auto it = markers.rbegin(); it != markers.rend(); ++it)
    io::DrawMarker(canvas, f.X(1000 * it->p(v.h)), f.Y(1000 * it->p(v.v)),
                   it->fitted ? kFittedCom : kTrueCom);
  canvas.CloseGroup();
}

// One line of the header: text, style, line height, at most `max_lines` wrapped.
struct HeaderLine {
  std::string text;
  io::TextStyle style;
  double height;
  int max_lines;
};

// Title, subtitle (mass, regions, what the views are), the source files and
// the contradiction warning.
std::vector<HeaderLine> HeaderLines(const InertiaFit& fit, const DensityPlotOptions& options) {
  const RegionModel* model = fit.region_model.get();
  std::vector<HeaderLine> lines;
  lines.push_back(
      {options.title.empty() ? absl::StrCat(ToString(fit.method), " fit") : options.title,
       {.size = 17, .bold = true},
       22,
       2});
  std::string subtitle = absl::StrFormat("mass %.4g kg", fit.params.mass);
  if (model != nullptr)
    absl::StrAppend(
        &subtitle,
        absl::StrFormat(", %d region%s (%s, outlined)", static_cast<int>(model->regions.size()),
                        model->regions.size() == 1 ? "" : "s", ToString(model->scheme)));
  else
    absl::StrAppend(&subtitle, ", no density regions (", ToString(fit.method),
                    " fit): silhouette only");
  absl::StrAppend(&subtitle, "; views along the fitted principal axes, mm from the fitted CoM");
  lines.push_back({subtitle, {.color = "#444"}, 17, 2});
  if (!options.source.empty())
    lines.push_back({absl::StrCat("source: ", options.source), {.color = "#444"}, 17, 2});
  if (fit.mesh_contradicted)
    lines.push_back({"mesh contradicted by the data: densities of the rejected fit",
                     {.bold = true, .color = "#b00020"},
                     17,
                     2});
  return lines;
}

// Draws the header (when `canvas` is set) wrapped to `width` px from
// baseline 26; returns the baseline below it.
double DrawHeader(io::SvgCanvas* canvas, const std::vector<HeaderLine>& lines, double width) {
  double y = 26;
  for (const HeaderLine& line : lines) {
    const double size = line.style.size > 0 ? line.style.size : 12;
    if (canvas != nullptr) {
      y = canvas->WrappedText(kLeft, y, line.text, width, line.style, line.height, line.max_lines);
    } else {
      y += line.height * io::WrapText(line.text, size, width, line.max_lines).size();
    }
  }
  return y;
}

// The legend (markers; the grey silhouette without regions) and, under it,
// the colour bar, from y = top in the right column.
void DrawKey(io::SvgCanvas& canvas, const Layout& layout, double top, const InertiaFit& fit,
             const std::vector<Marker>& markers, const DensityColors& colors,
             const io::ColorRamp& ramp) {
  std::vector<io::LegendEntry> entries;
  for (const Marker& m : markers)
    entries.push_back(
        {.label = m.fitted ? "fitted CoM"
                  : 1000 * m.p.norm() < 0.01
                      ? "true CoM (within 0.01 mm of the fitted)"
                      : absl::StrFormat("true CoM (%.3g mm from the fitted)", 1000 * m.p.norm()),
         .swatch = io::LegendEntry::Swatch::kMarker,
         .marker = m.fitted ? kFittedCom : kTrueCom});
  if (fit.region_model == nullptr)
    entries.push_back({.label = "mesh (no density regions)",
                       .swatch = io::LegendEntry::Swatch::kBox,
                       .color = io::HexColor(kGrey)});
  else
    entries.push_back(
        {.label = "outline of a region or part", .line = io::Stroke{"#202020", 1, ""}});
  canvas.OpenGroup("id=\"legend\"");
  const double end = io::DrawLegend(canvas, layout.column_x, top + 14, entries, 24, kColumn - 10);
  canvas.CloseGroup();
  if (fit.region_model == nullptr) return;
  io::ColorBar bar{.x = layout.column_x,
                   .y = end + 28,
                   .height = kBarHeight,
                   .lo = 0,
                   .hi = colors.bar_top,
                   .ticks = colors.bar_ticks,
                   .title = "density (kg/m\xc2\xb3)"};
  if (fit.densities.size() <= 64)
    for (const InertiaFit::RegionDensity& d : fit.densities)
      bar.marks.emplace_back(d.density,
                             absl::StrFormat("%s: %.4g kg/m\xc2\xb3", d.label, d.density));
  io::DrawColorBar(canvas, bar, ramp);
}

// The key's height from its top (legend rows and the colour bar with its title).
double KeyHeight(const InertiaFit& fit, const std::vector<Marker>& markers) {
  const double legend = 24 * (markers.size() + 1.0);
  return fit.region_model == nullptr ? legend + 14 : legend + 14 + 28 + kBarHeight + 10;
}

}  // namespace

absl::StatusOr<std::string> DensityPlotSvg(const io::TriangleMesh& mesh, const InertiaFit& fit,
                                           const DensityPlotOptions& options) {
  TF_RETURN_IF_ERROR(CheckInputs(mesh, fit));
  const PrincipalGeometry geometry = InPrincipalFrame(mesh, fit, options);
  Layout layout = PlaceViews(geometry);
  const io::ColorRamp ramp = io::ColorRamp::Viridis();
  const DensityColors colors = ColorByDensity(mesh, fit, ramp);
  // Back faces are hidden only on a closed, outward-oriented surface.
  const io::MeshCheck check = io::CheckMesh(mesh);
  std::vector<int> color_class;
  const std::string style = ColorClasses(colors.triangle, &color_class);
  const MeshPaint paint{mesh, geometry.p, color_class,
                        check.closed && check.consistently_oriented && check.volume > 0};

  const std::vector<HeaderLine> header = HeaderLines(fit, options);
  const double text_width = layout.width - kLeft - 10;
  const double top =
      DrawHeader(nullptr, header, text_width) + 18;  // the panels' titles above `top`
  for (io::PlotFrame& f : layout.frames) f.top += top;
  const double height = std::ceil(top + std::max(layout.bottom, KeyHeight(fit, geometry.markers)));
  io::SvgCanvas canvas(layout.width, height, 12);
  DrawHeader(&canvas, header, text_width);
  canvas.Raw(style);
  const std::vector<RegionEdge> edges = RegionBoundaries(mesh, fit.region_model.get());
  for (int i = 0; i < 3; ++i) DrawView(canvas, i, layout, paint, edges, geometry.markers);
  DrawKey(canvas, layout, top, fit, geometry.markers, colors, ramp);
  return canvas.Finish();
}

}  // namespace tactforce::inertia
