// The SVG picture of a DENSITY fit (density_plot.h).
//
// The project's SVG helpers cannot be used here: sim/experiment's svg.h
// renders line plots only, keeps its escaping and tick helpers private, and
// sits in a library (MuJoCo) that the inertia library must not depend on;
// estimator/audit's plot is private to report.cc. The two small helpers this
// file needs (text escaping, "nice" tick steps) are therefore local.
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
#include <limits>
#include <numeric>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace tactforce::inertia {
namespace {

using io::TriangleMesh;

constexpr uint32_t kGrey = 0xd0d0d0;       // no region / no region model
constexpr double kMaxPanelsWidth = 960;    // px, the three panels together
constexpr double kMaxPanelHeight = 420;    // px
constexpr double kMinPanelSize = 90;       // px, so that ticks and labels fit
constexpr double kPad = 10;                // px between the mesh and a panel's frame
constexpr double kGrid = 0.5;            // px: vertices snap to this grid (integer path coordinates)
constexpr double kSeamStroke = 0.5;        // px, same colour as the fill: hides anti-aliasing seams

// A sequential, perceptually ordered ramp from dark purple through blue and
// green to yellow (viridis-like), linear in sRGB between five anchors.
constexpr std::array<uint32_t, 5> kRamp = {0x440154, 0x3b528b, 0x21918c, 0x5ec962, 0xfde725};

uint32_t RampColor(double t) {
  if (!std::isfinite(t)) t = 0;
  t = std::clamp(t, 0.0, 1.0) * (kRamp.size() - 1);
  const int i = std::min(static_cast<int>(t), static_cast<int>(kRamp.size()) - 2);
  const double f = t - i;
  uint32_t out = 0;
  for (int shift : {16, 8, 0}) {
    const double a = (kRamp[i] >> shift) & 0xff, b = (kRamp[i + 1] >> shift) & 0xff;
    out |= static_cast<uint32_t>(std::lround(a + f * (b - a))) << shift;
  }
  return out;
}

std::string Hex(uint32_t rgb) { return absl::StrFormat("#%06x", rgb & 0xffffff); }

std::string Escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

// 1, 2 or 5 times a power of ten, at least `raw`.
double NiceStep(double raw) {
  if (!(raw > 0) || !std::isfinite(raw)) return 1.0;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * mag >= raw * (1 - 1e-12)) return m * mag;
  return 10 * mag;
}

// Tick label: multiples of `step`, without -0 or rounding noise.
std::string TickLabel(double v, double step) {
  v = std::round(v / step) * step;
  if (std::abs(v) < 1e-9 * step) v = 0;
  return absl::StrFormat("%.6g", v);
}

// Appends an integer to a path; a leading space unless the number is
// negative (its sign separates it) or it follows a command letter.
void AppendCoordinate(std::string* d, long v, bool after_command) {
  if (!after_command && v >= 0) d->push_back(' ');
  absl::StrAppend(d, v);
}

// One view: the plane of principal axes `h` (right) and `v` (up), seen from
// the side of h x v.
struct View {
  int h, v, k;       // k: the axis looked along
  double depth_sign; // depth = depth_sign * coordinate k (larger: nearer)
};
constexpr std::array<View, 3> kViews = {{{0, 1, 2, +1.0}, {0, 2, 1, -1.0}, {1, 2, 0, +1.0}}};
const char* const kMomentName[3] = {"smallest", "middle", "largest"};

struct Marker {
  Vec3 p;  // principal frame, m
  bool fitted;
};

}  // namespace

absl::StatusOr<std::string> DensityPlotSvg(const io::TriangleMesh& mesh, const InertiaFit& fit,
                                           const DensityPlotOptions& options) {
  if (mesh.vertices.empty() || mesh.triangles.empty())
    return absl::InvalidArgumentError("density plot: the mesh is empty");
  const int nv = static_cast<int>(mesh.vertices.size());
  for (size_t t = 0; t < mesh.triangles.size(); ++t)
    for (int i : mesh.triangles[t])
      if (i < 0 || i >= nv)
        return absl::InvalidArgumentError(absl::StrCat("density plot: mesh.triangles[", t, "]: vertex index ", i,
                                                       " out of range (", nv, " vertices)"));
  for (int i = 0; i < nv; ++i)
    if (!mesh.vertices[i].allFinite())
      return absl::InvalidArgumentError(absl::StrCat("density plot: mesh.vertices[", i, "]: not finite"));
  const RegionModel* model = fit.region_model.get();
  if (model != nullptr) {
    if (model->triangle_region.size() != mesh.triangles.size())
      return absl::InvalidArgumentError(absl::StrCat(
          "density plot: the mesh has ", mesh.triangles.size(), " triangles but the fit's region model has ",
          model->triangle_region.size(), " (not the mesh that was fitted)"));
    if (fit.densities.size() != model->regions.size())
      return absl::InvalidArgumentError(absl::StrCat("density plot: the fit has ", fit.densities.size(),
                                                     " densities for ", model->regions.size(), " regions"));
  }
  Eigen::Matrix3d axes = fit.principal_axes;
  if (!axes.allFinite() || std::abs(axes.determinant()) < 0.5) axes = Eigen::Matrix3d::Identity();
  if (axes.determinant() < 0) axes.col(2) = -axes.col(2);  // right-handed, for the back-face test
  const bool com_finite = fit.params.com.allFinite();
  const Vec3 origin = com_finite ? fit.params.com : Vec3::Zero();

  // Vertices in the principal frame, from the fitted CoM.
  std::vector<Vec3> p(nv);
  for (int i = 0; i < nv; ++i) p[i] = axes.transpose() * (mesh.vertices[i] - origin);
  std::vector<Marker> markers;
  if (com_finite) markers.push_back({Vec3::Zero(), true});
  if (options.true_com && options.true_com->allFinite())
    markers.push_back({axes.transpose() * (*options.true_com - origin), false});
  Vec3 lo = p[0], hi = p[0];
  for (const Vec3& q : p) lo = lo.cwiseMin(q), hi = hi.cwiseMax(q);
  for (const Marker& m : markers) lo = lo.cwiseMin(m.p), hi = hi.cwiseMax(m.p);
  Vec3 extent = hi - lo;
  const double size = std::max(extent.maxCoeff(), 1e-9);
  for (int a = 0; a < 3; ++a) {
    if (extent(a) < 1e-6 * size) {  // a flat mesh: give the axis some room
      lo(a) -= 0.5e-6 * size, hi(a) += 0.5e-6 * size;
      extent(a) = hi(a) - lo(a);
    }
  }

  // One scale (px per metre) for all three panels.
  double width_m = 0;
  double height_m = 0;
  for (const View& v : kViews) width_m += extent(v.h), height_m = std::max(height_m, extent(v.v));
  const double scale = std::min(kMaxPanelsWidth / width_m, kMaxPanelHeight / height_m);
  // Panel sizes in metres (at least kMinPanelSize px), centred on the mesh.
  std::array<Eigen::Vector2d, 3> panel_lo, panel_hi;
  double panel_h_px = 0;
  for (int i = 0; i < 3; ++i) {
    const View& v = kViews[i];
    for (int j = 0; j < 2; ++j) {
      const int a = j == 0 ? v.h : v.v;
      const double half = 0.5 * std::max(extent(a), (kMinPanelSize - 2 * kPad) / scale) + kPad / scale;
      const double mid = 0.5 * (lo(a) + hi(a));
      panel_lo[i](j) = mid - half;
      panel_hi[i](j) = mid + half;
    }
  }
  for (int i = 0; i < 3; ++i) panel_h_px = std::max(panel_h_px, (panel_hi[i](1) - panel_lo[i](1)) * scale);
  // Every panel gets the same height (the tallest), keeping the scale.
  for (int i = 0; i < 3; ++i) {
    const double grow = 0.5 * (panel_h_px / scale - (panel_hi[i](1) - panel_lo[i](1)));
    panel_lo[i](1) -= grow;
    panel_hi[i](1) += grow;
  }

  // Colours per triangle.
  double max_density = 0;
  if (model != nullptr)
    for (const InertiaFit::RegionDensity& d : fit.densities)
      if (std::isfinite(d.density)) max_density = std::max(max_density, d.density);
  // The bar runs from 0 to a round number at or above the largest density
  // (0 to 1000 when every density is 0).
  const double bar_max = max_density > 0 ? max_density : 1000.0;
  const double density_step = NiceStep(bar_max / 5);
  const double density_top = std::ceil(bar_max / density_step * (1 - 1e-12)) * density_step;
  std::vector<uint32_t> region_color;
  if (model != nullptr)
    for (const InertiaFit::RegionDensity& d : fit.densities)
      region_color.push_back(std::isfinite(d.density) ? RampColor(d.density / density_top) : kGrey);
  std::vector<uint32_t> color(mesh.triangles.size(), kGrey);
  if (model != nullptr) {
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const int r = model->triangle_region[t];
      if (r >= 0 && r < static_cast<int>(region_color.size())) color[t] = region_color[r];
    }
  }
  // Back faces are hidden only on a closed, outward-oriented surface.
  const io::MeshCheck check = io::CheckMesh(mesh);
  const bool cull = check.closed && check.consistently_oriented && check.volume > 0;

  // Layout.
  const double left = 64, gap = 64, top = 96, bottom = 56, column = 190;
  std::array<double, 3> panel_x, panel_w;
  std::array<std::string, 3> panel_title;
  double x = left;
  for (int i = 0; i < 3; ++i) {
    panel_x[i] = x;
    panel_w[i] = (panel_hi[i](0) - panel_lo[i](0)) * scale;
    panel_title[i] = absl::StrFormat("along axis %d (%s moment)", kViews[i].k + 1, kMomentName[kViews[i].k]);
    // A narrow panel still leaves room for its title (bold 12 px: ~8.5 px a character).
    x += std::max(panel_w[i], 8.5 * panel_title[i].size() - gap + 16) + gap;
  }
  const double column_x = x - gap + 40;
  // Legend in the header, right of the panels; the colour bar beside the panels.
  const double bar_top = top, bar_h = std::clamp(panel_h_px, 150.0, 260.0);
  const double width = std::ceil(column_x + column);
  const double height = std::ceil(std::max(top + panel_h_px + bottom, bar_top + bar_h + 30));

  std::string s = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" height=\"%g\" viewBox=\"0 0 %g %g\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
      width, height, width, height);
  const std::string title = options.title.empty() ? absl::StrCat(ToString(fit.method), " fit") : options.title;
  absl::StrAppendFormat(&s, "<text x=\"%g\" y=\"26\" font-size=\"17\" font-weight=\"bold\">%s</text>\n", left,
                        Escape(title));
  std::string subtitle = absl::StrFormat("mass %.4g kg", fit.params.mass);
  if (model != nullptr)
    absl::StrAppend(&subtitle, absl::StrFormat(", %d region%s (%s)", static_cast<int>(model->regions.size()),
                                               model->regions.size() == 1 ? "" : "s", ToString(model->scheme)));
  else
    absl::StrAppend(&subtitle, ", no density regions (", ToString(fit.method), " fit): silhouette only");
  absl::StrAppend(&subtitle, "; views along the fitted principal axes, mm from the fitted CoM");
  absl::StrAppendFormat(&s, "<text x=\"%g\" y=\"46\" fill=\"#444\">%s</text>\n", left, Escape(subtitle));
  if (fit.mesh_contradicted)
    absl::StrAppendFormat(&s,
                          "<text x=\"%g\" y=\"64\" fill=\"#b00020\" font-weight=\"bold\">mesh contradicted by the "
                          "data: densities of the rejected fit</text>\n",
                          left);

  // Ticks about every 80 px, but at least three on an axis (finer on short ones).
  const double tick_step_mm = NiceStep(80.0 / scale * 1000.0);

  // One CSS class per colour ("c0", "c1", ...): a path names its class only.
  std::vector<uint32_t> palette(color.begin(), color.end());
  std::sort(palette.begin(), palette.end());
  palette.erase(std::unique(palette.begin(), palette.end()), palette.end());
  std::vector<int> color_class(color.size());
  for (size_t t = 0; t < color.size(); ++t)
    color_class[t] = static_cast<int>(std::lower_bound(palette.begin(), palette.end(), color[t]) - palette.begin());
  absl::StrAppendFormat(&s, "<style>.mesh path{stroke-width:%gpx;stroke-linejoin:round}", kSeamStroke / kGrid);
  for (size_t i = 0; i < palette.size(); ++i)
    absl::StrAppend(&s, ".c", i, "{fill:", Hex(palette[i]), ";stroke:", Hex(palette[i]), "}");
  absl::StrAppend(&s, "</style>\n");
  std::vector<int> order(mesh.triangles.size());
  std::vector<double> depth(mesh.triangles.size());
  for (int i = 0; i < 3; ++i) {
    const View& v = kViews[i];
    const double px0 = panel_x[i], py0 = top;
    auto X = [&](double u) { return px0 + (u - panel_lo[i](0)) * scale; };
    auto Y = [&](double w) { return py0 + (panel_hi[i](1) - w) * scale; };
    absl::StrAppendFormat(&s, "<g id=\"view-%d\">\n", i + 1);
    absl::StrAppendFormat(&s, "<text x=\"%.1f\" y=\"%.1f\" font-weight=\"bold\">%s</text>\n", px0, py0 - 8,
                          panel_title[i]);
    // Ticks and grid, below the mesh.
    for (int j = 0; j < 2; ++j) {
      const double lo_mm = panel_lo[i](j) * 1000, hi_mm = panel_hi[i](j) * 1000;
      const double step = std::min(tick_step_mm, NiceStep((hi_mm - lo_mm) / 4));
      for (double t = std::ceil(lo_mm / step) * step; t <= hi_mm; t += step) {
        if (j == 0) {
          const double xx = X(t / 1000);
          absl::StrAppendFormat(&s,
                                "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#eee\"/><text "
                                "x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" font-size=\"11\">%s</text>\n",
                                xx, xx, py0, py0 + panel_h_px, xx, py0 + panel_h_px + 14,
                                TickLabel(t, step));
        } else {
          const double yy = Y(t / 1000);
          absl::StrAppendFormat(&s,
                                "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#eee\"/><text "
                                "x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\" font-size=\"11\">%s</text>\n",
                                px0, px0 + panel_w[i], yy, yy, px0 - 4, yy + 4, TickLabel(t, step));
        }
      }
    }
    absl::StrAppendFormat(&s, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">axis %d (mm)</text>\n",
                          px0 + panel_w[i] / 2, py0 + panel_h_px + 32, v.h + 1);
    const double ly = py0 + panel_h_px / 2;
    absl::StrAppendFormat(&s,
                          "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\" transform=\"rotate(-90 %.1f %.1f)\">"
                          "axis %d (mm)</text>\n",
                          px0 - 40, ly, px0 - 40, ly, v.v + 1);

    // The mesh, far to near, vertices snapped to a kGrid px grid.
    std::iota(order.begin(), order.end(), 0);
    for (size_t t = 0; t < mesh.triangles.size(); ++t) {
      const auto& tri = mesh.triangles[t];
      depth[t] = v.depth_sign * (p[tri[0]](v.k) + p[tri[1]](v.k) + p[tri[2]](v.k));
    }
    std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return depth[a] < depth[b]; });
    absl::StrAppendFormat(&s, "<g class=\"mesh\" transform=\"scale(%g)\">\n", kGrid);
    std::string d;
    int current = -1;
    auto flush = [&] {
      if (current >= 0) absl::StrAppend(&s, "<path class=\"c", current, "\" d=\"", d, "\"/>\n");
      current = -1;
      d.clear();
    };
    for (int t : order) {
      const auto& tri = mesh.triangles[t];
      std::array<double, 6> e;  // px
      std::array<long, 6> c;    // grid units
      for (int k = 0; k < 3; ++k) {
        e[2 * k] = X(p[tri[k]](v.h));
        e[2 * k + 1] = Y(p[tri[k]](v.v));
        c[2 * k] = std::lround(e[2 * k] / kGrid);
        c[2 * k + 1] = std::lround(e[2 * k + 1] / kGrid);
      }
      // Twice the signed area, positive when counter-clockwise on the page
      // (y down: clockwise in the numbers), i.e. facing us. Facing is decided
      // on the exact projection; a snapped triangle of no area covers nothing.
      auto area2 = [](const auto& q) {
        return -(static_cast<double>(q[2] - q[0]) * (q[5] - q[1]) - static_cast<double>(q[4] - q[0]) * (q[3] - q[1]));
      };
      if (cull && !(area2(e) > 0)) continue;
      if (area2(c) == 0) continue;
      const int cls = color_class[t];
      if (cls != current) {
        flush();
        current = cls;
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
    absl::StrAppend(&s, "</g>\n");
    absl::StrAppendFormat(&s,
                          "<rect class=\"frame\" x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
                          "stroke=\"#888\"/>\n",
                          px0, py0, panel_w[i], panel_h_px);
    // CoM markers on top: the true one first, so that the fitted cross stays visible.
    for (auto it = markers.rbegin(); it != markers.rend(); ++it) {
      const double mx = X(it->p(v.h)), my = Y(it->p(v.v));
      if (it->fitted) {
        absl::StrAppendFormat(&s,
                              "<g class=\"fitted-com\"><path d=\"M%.1f %.1fh14M%.1f %.1fv14\" stroke=\"white\" "
                              "stroke-width=\"4\"/><path d=\"M%.1f %.1fh14M%.1f %.1fv14\" stroke=\"black\" "
                              "stroke-width=\"2\"/></g>\n",
                              mx - 7, my, mx, my - 7, mx - 7, my, mx, my - 7);
      } else {
        absl::StrAppendFormat(&s,
                              "<g class=\"true-com\"><circle cx=\"%.1f\" cy=\"%.1f\" r=\"6\" fill=\"none\" "
                              "stroke=\"white\" stroke-width=\"4\"/><circle cx=\"%.1f\" cy=\"%.1f\" r=\"6\" "
                              "fill=\"none\" stroke=\"#e4007c\" stroke-width=\"2\"/></g>\n",
                              mx, my, mx, my);
      }
    }
    absl::StrAppend(&s, "</g>\n");
  }

  // Legend.
  double y = -2;
  absl::StrAppend(&s, "<g id=\"legend\">");
  for (const Marker& m : markers) {
    y += 22;
    if (m.fitted)
      absl::StrAppendFormat(&s,
                            "<path d=\"M%.1f %.1fh14M%.1f %.1fv14\" stroke=\"black\" stroke-width=\"2\"/><text "
                            "x=\"%.1f\" y=\"%.1f\">fitted CoM</text>\n",
                            column_x, y, column_x + 7, y - 7, column_x + 22, y + 4);
    else
      absl::StrAppendFormat(&s,
                            "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"6\" fill=\"none\" stroke=\"#e4007c\" "
                            "stroke-width=\"2\"/><text x=\"%.1f\" y=\"%.1f\">true CoM</text>\n",
                            column_x + 7, y, column_x + 22, y + 4);
  }
  if (model == nullptr) {
    y += 22;
    absl::StrAppendFormat(&s,
                          "<rect x=\"%.1f\" y=\"%.1f\" width=\"14\" height=\"10\" fill=\"%s\"/><text x=\"%.1f\" "
                          "y=\"%.1f\">mesh (no density regions)</text>\n",
                          column_x, y - 5, Hex(kGrey), column_x + 22, y + 4);
  }
  absl::StrAppend(&s, "</g>\n");

  // Colour bar, 0 at the bottom, with each region's density marked.
  if (model != nullptr) {
    const double bx = column_x, bw = 18;
    absl::StrAppend(&s, "<g id=\"colour-bar\">\n<defs><linearGradient id=\"density-ramp\" x1=\"0\" y1=\"1\" "
                        "x2=\"0\" y2=\"0\">");
    for (size_t i = 0; i < kRamp.size(); ++i)
      absl::StrAppendFormat(&s, "<stop offset=\"%g\" stop-color=\"%s\"/>", double(i) / (kRamp.size() - 1),
                            Hex(kRamp[i]));
    absl::StrAppend(&s, "</linearGradient></defs>\n");
    absl::StrAppendFormat(&s, "<text x=\"%.1f\" y=\"%.1f\">density (kg/m³)</text>\n", bx, bar_top - 12);
    absl::StrAppendFormat(&s,
                          "<rect x=\"%.1f\" y=\"%.1f\" width=\"%g\" height=\"%g\" fill=\"url(#density-ramp)\" "
                          "stroke=\"#444\"/>\n",
                          bx, bar_top, bw, bar_h);
    auto BY = [&](double rho) { return bar_top + bar_h * (1 - rho / density_top); };
    for (double t = 0; t <= density_top * (1 + 1e-9); t += density_step)
      absl::StrAppendFormat(&s,
                            "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#444\"/><text x=\"%.1f\" "
                            "y=\"%.1f\" font-size=\"11\">%s</text>\n",
                            bx + bw, bx + bw + 4, BY(t), BY(t), bx + bw + 7, BY(t) + 4,
                            TickLabel(t, density_step));
    if (fit.densities.size() <= 64)
      for (const InertiaFit::RegionDensity& d : fit.densities)
        if (std::isfinite(d.density))
          absl::StrAppendFormat(&s,
                                "<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"white\" "
                                "stroke-width=\"1\"><title>%s: %.4g kg/m³</title></line>\n",
                                bx + 2, bx + bw - 2, BY(d.density), BY(d.density), Escape(d.label), d.density);
    absl::StrAppend(&s, "</g>\n");
  }
  absl::StrAppend(&s, "</svg>\n");
  return s;
}

}  // namespace tactforce::inertia
