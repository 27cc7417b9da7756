// The SVG figures of plan_plot.h: three orthographic views of a PlanScene
// (x-y, x-z, y-z, equal scale in both axes and in every view), a legend
// with the units and the force scale, and small multiples for trajectories.
// Every figure has one length scale and one force scale (N per m), chosen so
// that the largest force glyph is under half the object's size.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/names.h"
#include "tactforce/api/plan_plot.h"
#include "tactforce/io/svg.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::api {
namespace {

using planner::Vec3;
using Point = std::pair<double, double>;

// A view: data axes a (right) and b (up); `depth` points toward the viewer
// when `toward` is +1, away when -1 (right-handed: a x b = toward * e_depth).
struct ViewAxes {
  int a, b, depth;
  double toward;
  const char* id;
  const char* title;
};
constexpr ViewAxes kViews[3] = {
    {0, 1, 2, +1, "view-xy", "x-y (z toward you)"},
    {0, 2, 1, -1, "view-xz", "x-z (y away from you)"},
    {1, 2, 0, +1, "view-yz", "y-z (x toward you)"},
};
constexpr const char* kAxisTitle[3] = {"x (m)", "y (m)", "z (m)"};

const char kConeColor[] = "#3182bd";
const char kForceColor[] = "#d62728";
const char kSpreadColor[] = "#ff7f0e";
const char kParameterSpreadColor[] = "#9467bd";
const char kComColor[] = "#2ca02c";
const char kGravityColor[] = "#6a3d9a";
const io::Stroke kNormalStroke{"#666", 1, "3,3"};

// Sizes of one figure's views (px).
struct Style {
  double view;  // side of a view's square frame
  double left;  // room left of a frame (tick labels, y title)
  double gap;   // between two frames
  double tick_font;
  double title_offset;  // axis titles from the frame
  double head;          // arrow heads
  double point;         // contact point radius
  double label_font;
};
constexpr Style kLarge{300, 64, 80, 11, 30, 9, 3.5, 11};
constexpr Style kSmall{170, 50, 62, 9, 25, 6, 2.5, 9};

// One length and force scale for every view of a figure.
struct Scale {
  double newtons_per_metre = 1;
  double cone_height = 1;    // N along the normal: the top of every drawn cone
  double normal_length = 0;  // m
  Vec3 centre = Vec3::Zero();
  double half = 0.05;  // m: every view shows centre +- half on both axes
  double metres_per_newton() const { return 1 / newtons_per_metre; }
};

// Data (object frame) to canvas px in one view.
struct Projector {
  io::PlotFrame frame;
  ViewAxes view;
  Point operator()(const Vec3& p) const { return {frame.X(p[view.a]), frame.Y(p[view.b])}; }
  double px_per_metre() const { return frame.width / (frame.x_hi - frame.x_lo); }
};

std::string GlyphGroup(const char* css_class, int contact, std::string_view extra = "") {
  return absl::StrFormat("class=\"%s\" data-contact=\"%d\"%s", css_class, contact, extra);
}

// The rim of a contact's drawn cone at height cone_height, angle phi about
// the normal from tangent1 (m, object frame).
Vec3 Rim(const ContactGlyph& c, const Scale& s, double phi) {
  const double m = s.metres_per_newton();
  const double r = c.friction * std::max(0.0, s.cone_height - c.apex_shift) * m;
  return c.position + s.cone_height * m * c.normal +
         r * (std::cos(phi) * c.tangent1 + std::sin(phi) * c.tangent2);
}

void ExtendByGlyph(const ContactGlyph& c, const Scale& s, Eigen::AlignedBox3d* box) {
  const double m = s.metres_per_newton();
  const Vec3 tip = c.has_force ? Vec3(c.position + m * c.force) : c.position;
  const Vec3 spread = m * (c.covariance.diagonal().cwiseMax(0).cwiseSqrt())
                              .cwiseMax(c.parameter_covariance.diagonal().cwiseMax(0).cwiseSqrt());
  box->extend(tip + spread);
  box->extend(tip - spread);
  box->extend(c.position + s.normal_length * c.normal);
  box->extend(c.position + c.apex_shift * m * c.normal);
  for (int j = 0; j < 16; ++j) box->extend(Rim(c, s, 2 * std::numbers::pi * j / 16));
}

// The cone height and the force scale: the largest force glyph (force plus
// its spread, or a cone's rim) is at most 0.45 x the object's size.
void ChooseForceScale(const std::vector<const PlanScene*>& scenes, double size, Scale* s) {
  double height = 0, shift = 0;
  for (const PlanScene* scene : scenes)
    for (const ContactGlyph& c : scene->contacts) {
      if (c.has_force) height = std::max(height, c.normal.dot(c.force));
      shift = std::max(shift, c.apex_shift);
    }
  s->cone_height = std::max(1.15 * height, 1.5 * shift);
  if (!(s->cone_height > 0)) s->cone_height = 1;
  double force = 0;
  for (const PlanScene* scene : scenes)
    for (const ContactGlyph& c : scene->contacts) {
      const double spread =
          std::sqrt(std::max({0.0, c.covariance.trace(), c.parameter_covariance.trace()}));
      force = std::max({force, (c.has_force ? c.force.norm() : 0.0) + spread,
                        s->cone_height * std::hypot(1.0, c.friction)});
    }
  s->newtons_per_metre = io::NiceStep(force / (0.45 * size));
}

Scale ChooseScale(const std::vector<const PlanScene*>& scenes) {
  Eigen::AlignedBox3d where;
  for (const PlanScene* scene : scenes) {
    where.extend(scene->com);
    for (const ContactGlyph& c : scene->contacts) where.extend(c.position);
  }
  double size = where.isEmpty() ? 0 : where.sizes().maxCoeff();
  if (!(size > 1e-9)) size = 0.1;
  Scale s;
  ChooseForceScale(scenes, size, &s);
  s.normal_length = 0.15 * size;
  Eigen::AlignedBox3d box = where;
  for (const PlanScene* scene : scenes)
    for (const ContactGlyph& c : scene->contacts) ExtendByGlyph(c, s, &box);
  // The gravity arrow: 0.2 of a view (0.4 x half) from the CoM, any way.
  for (int pass = 0; pass < 2; ++pass) {
    s.centre = box.center();
    s.half = 0.55 * box.sizes().maxCoeff();
    if (!(s.half > 0)) s.half = 0.05;
    for (const PlanScene* scene : scenes) {
      const double g = scene->gravity.norm();
      if (g > 0) box.extend(scene->com + 0.4 * s.half * scene->gravity / g);
    }
  }
  return s;
}

// ---- Glyphs -------------------------------------------------------------------

// The robust cone: a pyramid's edges and rim, or an exact cone's rim and the
// two generators on its outline in this view (none when seen along its axis).
void DrawCone(io::SvgCanvas& canvas, const Projector& at, const ContactGlyph& c, const Scale& s,
              int i) {
  canvas.OpenGroup(
      GlyphGroup("cone", i, absl::StrFormat(" fill=\"%s\" fill-opacity=\"0.1\"", kConeColor)));
  const io::Stroke stroke{kConeColor, 1, ""};
  const Point apex = at(c.position + c.apex_shift * s.metres_per_newton() * c.normal);
  const int sides = c.cone_sides > 0 ? c.cone_sides : 64;
  std::vector<Point> rim;
  for (int j = 0; j < sides; ++j)
    rim.push_back(at(Rim(c, s, 2 * std::numbers::pi * (j + 0.5) / sides)));
  canvas.Polygon(rim, stroke, kConeColor);
  std::vector<Point> edges = rim;  // a pyramid's edges
  if (c.cone_sides == 0) {         // an exact cone's outline: n x (mu n - u(phi)) . e_depth = 0
    edges.clear();
    const int d = at.view.depth;
    const double a = c.tangent1[d], b = c.tangent2[d], r = std::hypot(a, b),
                 want = c.friction * c.normal[d];
    if (r > 1e-12 && std::abs(want) <= r) {
      const double mid = std::atan2(b, a), spread = std::acos(std::clamp(want / r, -1.0, 1.0));
      edges = {at(Rim(c, s, mid - spread)), at(Rim(c, s, mid + spread))};
    }
  }
  std::string d;
  for (const Point& e : edges)
    absl::StrAppendFormat(&d, "M%.1f,%.1fL%.1f,%.1f", apex.first, apex.second, e.first, e.second);
  if (!d.empty()) canvas.Path(d, stroke);
  canvas.CloseGroup();
}

// The 1-sigma ellipse of S_ii projected on the view, at the force's tip: the
// shadow of {x : x^T S^-1 x <= 1} on a coordinate plane has the 2x2 block of
// S as its matrix. At least 0.6 px on each axis, so a zero spread shows.
void DrawSpread(io::SvgCanvas& canvas, const Projector& at, const ContactGlyph& c, const Scale& s,
                int i, const Eigen::Matrix3d& covariance, const char* css_class,
                const char* color) {
  canvas.OpenGroup(GlyphGroup(css_class, i));
  const Point tip =
      at(c.has_force ? Vec3(c.position + s.metres_per_newton() * c.force) : c.position);
  const double k = s.metres_per_newton() * at.px_per_metre();  // px per N
  const int a = at.view.a, b = at.view.b;
  const double saa = covariance(a, a) * k * k, sbb = covariance(b, b) * k * k,
               sab = covariance(a, b) * k * k;
  const double mean = 0.5 * (saa + sbb), dev = std::hypot(0.5 * (saa - sbb), sab);
  const double rx = std::max(0.6, std::sqrt(std::max(0.0, mean + dev)));
  const double ry = std::max(0.6, std::sqrt(std::max(0.0, mean - dev)));
  const double theta = 0.5 * std::atan2(2 * sab, saa - sbb);  // major axis, data angle (y up)
  const io::Stroke stroke{color, 1.5, ""};
  canvas.Ellipse(tip.first, tip.second, rx, ry, -theta * 180 / std::numbers::pi, "none", &stroke);
  canvas.CloseGroup();
}

void DrawContact(io::SvgCanvas& canvas, const Projector& at, const ContactGlyph& c, const Scale& s,
                 const Style& style, int i, io::LabelPlacer& labels) {
  const Point p = at(c.position);
  canvas.OpenGroup(GlyphGroup("normal", i));
  const Point n = at(c.position + s.normal_length * c.normal);
  canvas.Line(p.first, p.second, n.first, n.second, kNormalStroke);
  canvas.CloseGroup();
  canvas.OpenGroup(GlyphGroup("force-arrow", i));
  if (c.has_force) {
    const Point tip = at(c.position + s.metres_per_newton() * c.force);
    io::DrawArrow(canvas, p.first, p.second, tip.first, tip.second, {kForceColor, 2, ""},
                  style.head);
  }
  canvas.CloseGroup();
  canvas.OpenGroup(GlyphGroup("contact-point", i));
  canvas.Circle(p.first, p.second, style.point, "black");
  const auto [lx, ly] = labels.Place(p.first, p.second, c.label, style.label_font);
  canvas.Text(lx, ly, c.label, {.size = style.label_font});
  canvas.CloseGroup();
}

// The CoM (ring and cross) and the gravity direction from it: an arrow of
// 0.2 x the view, or, seen end on, a circle with a dot (toward you) or a
// cross (away) beside the CoM.
void DrawComAndGravity(io::SvgCanvas& canvas, const Projector& at, const PlanScene& scene,
                       double view_px, io::LabelPlacer& labels) {
  const Point com = at(scene.com);
  canvas.OpenGroup("class=\"com\"");
  io::DrawMarker(canvas, com.first, com.second,
                 {.shape = io::MarkerShape::kRing, .color = kComColor, .size = 12});
  io::DrawMarker(canvas, com.first, com.second,
                 {.color = kComColor, .size = 12, .line_width = 1.5});
  canvas.CloseGroup();
  canvas.OpenGroup("class=\"gravity\"");
  const double g = scene.gravity.norm(), length = 0.2 * view_px;
  const io::Stroke stroke{kGravityColor, 2, ""};
  if (!(g > 0)) {
    canvas.Text(com.first + 10, com.second - 10, "g = 0", {.color = kGravityColor});
    labels.Block(io::TextBoxOf(com.first + 10, com.second - 10, "g = 0", canvas.font_size(),
                               io::TextAnchor::kStart));
  } else {
    const double dx = scene.gravity[at.view.a] / g * length,
                 dy = -scene.gravity[at.view.b] / g * length;
    if (std::hypot(dx, dy) >= 4) {
      io::DrawArrow(canvas, com.first, com.second, com.first + dx, com.second + dy, stroke, 9);
      canvas.Text(com.first + dx + 4, com.second + dy + 4, "g", {.color = kGravityColor});
      labels.Block(io::TextBoxOf(com.first + dx + 4, com.second + dy + 4, "g", canvas.font_size(),
                                 io::TextAnchor::kStart));
    } else {
      const double x = com.first + 16, y = com.second - 16;
      canvas.Circle(x, y, 6, "none", &stroke);
      if (scene.gravity[at.view.depth] * at.view.toward > 0) {
        canvas.Circle(x, y, 1.5, kGravityColor);
      } else {
        canvas.Path(absl::StrFormat("M%.1f,%.1fl8,8m0,-8l-8,8", x - 4, y - 4),
                    {kGravityColor, 1.5, ""});
      }
      canvas.Text(x + 9, y + 4, "g", {.color = kGravityColor});
      labels.Block({x - 7, y - 7, x + 7, y + 7});
      labels.Block(io::TextBoxOf(x + 9, y + 4, "g", canvas.font_size(), io::TextAnchor::kStart));
    }
  }
  canvas.CloseGroup();
}

// One view: axes, CoM and gravity, cones and normals under the forces,
// spreads and points; `id` is unique in the document.
void DrawView(io::SvgCanvas& canvas, const io::PlotFrame& frame, const ViewAxes& view,
              const std::string& id, const PlanScene& scene, const Scale& s, const Style& style) {
  canvas.OpenGroup(absl::StrFormat("class=\"view\" id=\"%s\"", id));
  canvas.Text(frame.left + frame.width / 2, frame.top - 7, view.title,
              {.size = style.label_font + 1, .bold = true, .anchor = io::TextAnchor::kMiddle});
  const io::AxisStyle x_axis{.title = kAxisTitle[view.a],
                             .title_offset = style.title_offset,
                             .tick_font_size = style.tick_font};
  io::AxisStyle y_axis = x_axis;
  y_axis.title = kAxisTitle[view.b];
  y_axis.title_offset = style.left - 12;
  io::DrawAxes(canvas, frame, io::AxisTicks(frame.x_lo, frame.x_hi, 4), x_axis,
               io::AxisTicks(frame.y_lo, frame.y_hi, 4), y_axis);
  const Projector at{frame, view};
  // Contact labels go where no other label, point or the CoM is.
  io::LabelPlacer labels({frame.left + 2, frame.top + 2, frame.right() - 2, frame.bottom() - 2});
  for (const ContactGlyph& c : scene.contacts) {
    const Point p = at(c.position);
    labels.Block({p.first - style.point, p.second - style.point, p.first + style.point,
                  p.second + style.point});
  }
  const Point com = at(scene.com);
  labels.Block({com.first - 6, com.second - 6, com.first + 6, com.second + 6});
  DrawComAndGravity(canvas, at, scene, style.view, labels);
  for (size_t i = 0; i < scene.contacts.size(); ++i)
    DrawCone(canvas, at, scene.contacts[i], s, static_cast<int>(i));
  for (size_t i = 0; i < scene.contacts.size(); ++i) {
    DrawContact(canvas, at, scene.contacts[i], s, style, static_cast<int>(i), labels);
    const ContactGlyph& c = scene.contacts[i];
    DrawSpread(canvas, at, c, s, static_cast<int>(i), c.covariance, "spread-ellipse", kSpreadColor);
    if (!c.parameter_covariance.isZero(0.0)) {
      DrawSpread(canvas, at, c, s, static_cast<int>(i), c.parameter_covariance,
                 "parameter-spread-ellipse", kParameterSpreadColor);
    }
  }
  io::DrawFrameOutline(canvas, frame, {"#444", 1, ""});
  canvas.CloseGroup();
}

// The three views in a row, frames `top` px from the canvas's top, the
// first frame's left edge at `left`.
void DrawViews(io::SvgCanvas& canvas, double left, double top, const std::string& id_prefix,
               const PlanScene& scene, const Scale& s, const Style& style) {
  for (int v = 0; v < 3; ++v) {
    const ViewAxes& view = kViews[v];
    const io::PlotFrame frame{left + v * (style.view + style.gap),
                              top,
                              style.view,
                              style.view,
                              s.centre[view.a] - s.half,
                              s.centre[view.a] + s.half,
                              s.centre[view.b] - s.half,
                              s.centre[view.b] + s.half};
    DrawView(canvas, frame, view, id_prefix + view.id, scene, s, style);
  }
}

double ViewsWidth(const Style& style) { return style.left + 3 * style.view + 2 * style.gap; }

// ---- Legend ---------------------------------------------------------------------

constexpr double kLegendRow = 18;  // px

// The legend's entries (what each glyph is, with the figure's scales).
std::vector<io::LegendEntry> PlotLegendEntries(const PlanScene& scene, const Scale& s) {
  const int sides = scene.contacts.empty() ? 0 : scene.contacts.front().cone_sides;
  const std::string cone =
      sides > 0
          ? absl::StrFormat(
                "robust friction pyramid (%d facets): apex moved along n by the largest facet "
                "tightening, so it lies inside every tightened row; drawn up to n\xc2\xb7"
                "f = %.3g N",
                sides, s.cone_height)
          : absl::StrFormat(
                "robust friction cone: apex moved along n by cone_shift / \xce\xbc (exactly the "
                "tightened cone); drawn up to n\xc2\xb7"
                "f = %.3g N",
                s.cone_height);
  using Entry = io::LegendEntry;
  std::vector<Entry> entries = {
      {.label = "contact point (m), with its name",
       .swatch = Entry::Swatch::kMarker,
       .marker = {.shape = io::MarkerShape::kBox, .size = 6}},
      {.label = "inward normal n (direction only)", .line = kNormalStroke},
      {.label = cone, .swatch = Entry::Swatch::kBox, .color = "#c6dbef"},
      {.label =
           absl::StrFormat("planned force f from the contact point, at %g N per m (1 N = %g mm)",
                           s.newtons_per_metre, 1000 / s.newtons_per_metre),
       .line = {kForceColor, 2, ""}},
      {.label = "1\xcf\x83 spread of f: the trusted ellipsoid's block S_ii (N\xc2\xb2), projected, "
                "at the force tip "
                "(same N per m)",
       .line = {kSpreadColor, 1.5, ""}},
      {.label = "centre of mass (m)",
       .swatch = Entry::Swatch::kMarker,
       .marker =
           {.shape = io::MarkerShape::kRing, .color = kComColor, .size = 12, .line_width = 1}},
      {.label = "gravity direction (fixed length; \xe2\x8a\x99 toward you, \xe2\x8a\x97 away)",
       .line = {kGravityColor, 2, ""}},
  };
  bool uncertain = false;
  for (const ContactGlyph& c : scene.contacts)
    uncertain = uncertain || !c.parameter_covariance.isZero(0.0);
  if (uncertain) {
    const Entry parameters{.label =
                               "1\xcf\x83 spread of f from the inertial parameters: (G\xe2\x81\xba "
                               "S_b G\xe2\x81\xba\xe1\xb5\x80)_ii, "
                               "S_b = Y S_\xcf\x80 Y\xe1\xb5\x80 (N\xc2\xb2), projected, at the "
                               "force tip (same N per m)",
                           .line = {kParameterSpreadColor, 1.5, ""}};
    entries.insert(entries.begin() + 5, parameters);
  }
  return entries;
}

// The height of the legend (heading and entries) wrapped to `width` px.
double PlotLegendHeight(const PlanScene& scene, const Scale& s, double font_size, double width) {
  return kLegendRow + io::LegendHeight(PlotLegendEntries(scene, s), font_size, kLegendRow, width);
}

// The legend under the views, wrapped to `width` px, its heading's baseline at
// y; returns the baseline below it.
double DrawPlotLegend(io::SvgCanvas& canvas, double x, double y, const PlanScene& scene,
                      const Scale& s, double width) {
  canvas.OpenGroup("id=\"legend\"");
  canvas.WrappedText(x, y, "Object frame, orthographic views; positions in m. Legend:", width,
                     {.bold = true}, 0, 1);
  const double end =
      io::DrawLegend(canvas, x, y + kLegendRow, PlotLegendEntries(scene, s), kLegendRow, width);
  canvas.CloseGroup();
  return end;
}

// The title (bold, wrapped), the settings and the source file under it, from
// baseline y within `width` px; returns the baseline below.
double DrawHeading(io::SvgCanvas& canvas, double x, double y, const std::string& title,
                   const PlanScene* scene, std::string_view source, double width,
                   double title_size) {
  y = canvas.WrappedText(x, y, title, width, {.size = title_size, .bold = true}, title_size + 4, 2);
  if (scene != nullptr) y = canvas.WrappedText(x, y, scene->settings, width, {}, 16, 2);
  if (!source.empty())
    y = canvas.WrappedText(x, y, "source: " + std::string(source), width, {.color = "#444"}, 16, 1);
  return y;
}

// The height DrawHeading takes.
double HeadingHeight(const std::string& title, const PlanScene* scene, std::string_view source,
                     double width, double title_size, double font_size) {
  double h = (title_size + 4) * io::WrapText(title, title_size, width, 2).size();
  if (scene != nullptr) h += 16 * io::WrapText(scene->settings, font_size, width, 2).size();
  if (!source.empty()) h += 16;
  return h;
}

std::string ForceLine(const ContactGlyph& c) {
  if (!c.has_force)
    return absl::StrFormat("%s: no force; cone apex shift %.3g N", c.label, c.apex_shift);
  // Components below 1e-9 |f| are round-off: printed as 0.
  const Vec3 f =
      c.force.unaryExpr([&](double v) { return std::abs(v) < 1e-9 * c.force.norm() ? 0.0 : v; });
  return absl::StrFormat(
      "%s: f = (%.3g, %.3g, %.3g) N, |f| = %.3g N, n\xc2\xb7"
      "f = %.3g N; cone apex shift %.3g N",
      c.label, f.x(), f.y(), f.z(), c.force.norm(), c.normal.dot(c.force), c.apex_shift);
}

// ---- Figures --------------------------------------------------------------------

std::string RenderPlan(const PlanScene& scene, std::string_view source) {
  const Style& style = kLarge;
  const Scale s = ChooseScale({&scene});
  const double width = ViewsWidth(style) + 30, text_width = width - style.left - 10, font = 12;
  const std::string title = absl::StrCat(
      "Plan: ", scene.status, scene.outcome.empty() ? "" : " \xe2\x80\x94 ", scene.outcome);
  const double views_top = 26 + HeadingHeight(title, &scene, source, text_width, 16, font) + 20;
  const double legend_top = views_top + style.view + 62;
  const double table_top = legend_top + PlotLegendHeight(scene, s, font, text_width) + 14;
  const double height = table_top + 16 * scene.contacts.size() + 16;
  io::SvgCanvas canvas(width, height, font);
  DrawHeading(canvas, style.left, 26, title, &scene, source, text_width, 16);
  DrawViews(canvas, style.left, views_top, "", scene, s, style);
  DrawPlotLegend(canvas, style.left, legend_top, scene, s, text_width);
  canvas.OpenGroup("id=\"contact-table\"");
  for (size_t i = 0; i < scene.contacts.size(); ++i)
    canvas.WrappedText(style.left, table_top + 16 * i, ForceLine(scene.contacts[i]), text_width, {},
                       16, 1);
  canvas.CloseGroup();
  return canvas.Finish();
}

std::string TrajectoryHeading(const v1::TrajectoryResponse& response, int steps,
                              const std::vector<int>& shown) {
  std::string out = absl::StrFormat(
      "Trajectory plan: %d steps (%d optimal, %d infeasible, %d failed); ", steps,
      response.optimal_steps(), response.infeasible_steps(), response.failed_steps());
  if (static_cast<int>(shown.size()) == steps) return absl::StrCat(out, "one panel per step");
  return absl::StrCat(out, "showing ", shown.size(),
                      " evenly spaced steps: ", absl::StrJoin(shown, ", "));
}

std::string RenderTrajectory(const std::vector<PlanScene>& scenes, const std::vector<int>& shown,
                             const std::string& heading, std::string_view source) {
  const Style& style = kSmall;
  std::vector<const PlanScene*> all;
  for (const PlanScene& scene : scenes) all.push_back(&scene);
  const Scale s = ChooseScale(all);
  const int columns = shown.size() > 2 ? 2 : 1;
  const int rows = (static_cast<int>(shown.size()) + columns - 1) / columns;
  const double panel_w = ViewsWidth(style) + 24, panel_h = 36 + style.view + 48, font = 12;
  const double width = columns * panel_w + 20, text_width = width - style.left - 10;
  const PlanScene* first = scenes.empty() ? nullptr : &scenes.front();
  const double top = 26 + HeadingHeight(heading, first, source, text_width, 15, font) + 8;
  const double legend_top = top + rows * panel_h + 16;
  const double legend_height = first == nullptr ? 0 : PlotLegendHeight(*first, s, font, text_width);
  io::SvgCanvas canvas(width, legend_top + legend_height + 16, font);
  DrawHeading(canvas, style.left, 26, heading, first, source, text_width, 15);
  for (size_t j = 0; j < shown.size(); ++j) {
    const double x = 10 + (j % columns) * panel_w, y = top + (j / columns) * panel_h;
    canvas.OpenGroup(absl::StrFormat("class=\"step-panel\" data-step=\"%d\"", shown[j]));
    const PlanScene& scene = scenes[j];
    canvas.WrappedText(x, y + 14,
                       absl::StrCat("step ", shown[j], ": ", scene.status,
                                    scene.outcome.empty() ? "" : ", ", scene.outcome),
                       panel_w - 20, {.bold = true}, 16, 1);
    DrawViews(canvas, x + style.left, y + 36, absl::StrCat("step", shown[j], "-"), scene, s, style);
    canvas.CloseGroup();
  }
  if (first != nullptr) DrawPlotLegend(canvas, style.left, legend_top, *first, s, text_width);
  return canvas.Finish();
}

}  // namespace

absl::StatusOr<std::string> PlanSvg(const v1::PlanRequest& request,
                                    const v1::PlanResponse& response, std::string_view source) {
  TF_ASSIGN_OR_RETURN(PlanCall call, FromProto(request));
  TF_ASSIGN_OR_RETURN(PlanScene scene, BuildPlanScene(call.problem, call.options, response));
  return RenderPlan(scene, source);
}

absl::StatusOr<std::string> TrajectorySvg(const v1::TrajectoryRequest& request,
                                          const v1::TrajectoryResponse& response,
                                          std::string_view source) {
  TF_ASSIGN_OR_RETURN(PlanCall call, FromProto(request.plan()));
  TF_ASSIGN_OR_RETURN(planner::TrajectoryProblem motion,
                      ToTrajectoryProblem(request, call.problem));
  const int steps = std::min(request.steps_size(), response.steps_size());
  const std::vector<int> shown = PlottedSteps(steps);
  std::vector<PlanScene> scenes;
  for (int k : shown) {
    absl::StatusOr<PlanScene> scene =
        BuildPlanScene(planner::StepProblem(motion, k), call.options, response.steps(k));
    if (!scene.ok()) return io::PrependPath(scene.status(), absl::StrCat("steps[", k, "]"));
    scenes.push_back(*std::move(scene));
  }
  return RenderTrajectory(scenes, shown, TrajectoryHeading(response, steps, shown), source);
}

}  // namespace tactforce::api
