// Plot elements of svg.h on top of SvgCanvas: axes (grid, tick labels,
// titles), rules, traces, scatter dots, markers, legends and colour bars.
// Tick labels sit 5 px off the frame (x labels clear of a y label at the
// bottom edge); a legend swatch's middle is 4 px above
// its label's baseline (about half the height of a lower-case letter).
#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/svg.h"

namespace tactforce::io {
namespace {

const Stroke kGridStroke{"#e6e6e6", 1, ""};

// Within [lo, hi] (either order), up to rounding.
bool Inside(double v, double lo, double hi) {
  const double slack = 1e-9 * std::abs(hi - lo);
  return v >= std::min(lo, hi) - slack && v <= std::max(lo, hi) + slack;
}

double FontSize(const SvgCanvas& canvas, double size) {
  return size > 0 ? size : canvas.font_size();
}

// Every k-th index so that about `max_points` remain.
size_t Stride(size_t n, size_t max_points) {
  return std::max<size_t>(1, n / std::max<size_t>(1, max_points));
}

}  // namespace

void DrawAxes(SvgCanvas& canvas, const PlotFrame& frame, const Ticks& x_ticks,
              const AxisStyle& x_style, const Ticks& y_ticks, const AxisStyle& y_style) {
  const double x_font = FontSize(canvas, x_style.tick_font_size),
               y_font = FontSize(canvas, y_style.tick_font_size);
  canvas.OpenGroup("class=\"x-ticks\"");
  double last_right = -std::numeric_limits<double>::infinity();
  for (double v : x_ticks.values) {
    if (!Inside(v, frame.x_lo, frame.x_hi)) continue;
    const double x = frame.X(v);
    if (x_style.grid) canvas.Line(x, frame.top, x, frame.bottom(), kGridStroke);
    const std::string label = TickLabel(v, x_ticks.step);
    const TextBox box =
        TextBoxOf(x, frame.bottom() + x_font + 5, label, x_font, TextAnchor::kMiddle);
    if (!x_style.tick_labels || box.left < last_right + 0.5 * x_font)
      continue;  // would touch its neighbour
    canvas.Text(x, frame.bottom() + x_font + 5, label,
                {.size = x_font, .anchor = TextAnchor::kMiddle});
    last_right = box.right;
  }
  canvas.CloseGroup();
  canvas.OpenGroup("class=\"y-ticks\"");
  double widest = 0;
  for (double v : y_ticks.values) {
    if (!Inside(v, frame.y_lo, frame.y_hi)) continue;
    const double y = frame.Y(v);
    if (y_style.grid) canvas.Line(frame.left, y, frame.right(), y, kGridStroke);
    if (!y_style.tick_labels) continue;
    const std::string label = TickLabel(v, y_ticks.step);
    canvas.Text(frame.left - 5, y + 0.35 * y_font, label,
                {.size = y_font, .anchor = TextAnchor::kEnd});
    widest = std::max(widest, TextWidth(label, y_font));
  }
  canvas.CloseGroup();
  // The x title's ascent must clear the tick labels' descent by 2 px.
  const double x_offset =
      std::max(x_style.title_offset, x_font + 5 + 0.25 * x_font + 2 + 0.8 * canvas.font_size());
  if (!x_style.title.empty())
    canvas.Text(frame.left + frame.width / 2, frame.bottom() + x_offset, x_style.title,
                {.anchor = TextAnchor::kMiddle});
  // The rotated title's descent must clear the widest tick label by 3 px.
  const double y_offset =
      std::max(y_style.title_offset, 5 + widest + 3 + 0.25 * canvas.font_size());
  if (!y_style.title.empty())
    canvas.Text(frame.left - y_offset, frame.top + frame.height / 2, y_style.title,
                {.anchor = TextAnchor::kMiddle, .vertical = true});
}

void DrawFrameOutline(SvgCanvas& canvas, const PlotFrame& frame, const Stroke& stroke,
                      std::string_view css_class) {
  canvas.Rect(frame.left, frame.top, frame.width, frame.height, "none", &stroke, css_class);
}

void DrawVerticalRule(SvgCanvas& canvas, const PlotFrame& frame, double x, const Stroke& stroke,
                      std::string_view label, std::string_view label_color) {
  if (!std::isfinite(x) || !Inside(x, frame.x_lo, frame.x_hi)) return;
  const double px = frame.X(x);
  canvas.Line(px, frame.top, px, frame.bottom(), stroke);
  if (!label.empty())
    canvas.Text(px + 3, frame.top + canvas.font_size() + 2, label,
                {.color = std::string(label_color)});
}

void DrawLineTrace(SvgCanvas& canvas, const PlotFrame& frame, const std::vector<double>& x,
                   const std::vector<double>& y, const Stroke& stroke, size_t max_points) {
  const size_t n = std::min(x.size(), y.size());
  std::string d;
  bool pen_down = false;
  for (size_t i = 0; i < n; i += Stride(n, max_points)) {
    if (!std::isfinite(x[i]) || !std::isfinite(y[i])) {
      pen_down = false;
      continue;
    }
    absl::StrAppendFormat(&d, "%s%.1f,%.1f", pen_down ? "L" : "M", frame.X(x[i]), frame.Y(y[i]));
    pen_down = true;
  }
  if (!d.empty()) canvas.Path(d, stroke);
}

void DrawScatter(SvgCanvas& canvas, const PlotFrame& frame, const std::vector<double>& x,
                 const std::vector<double>& y, std::string_view color, double radius,
                 double opacity, size_t max_points) {
  const size_t n = std::min(x.size(), y.size());
  canvas.OpenGroup(absl::StrFormat("fill=\"%s\" fill-opacity=\"%g\"", SvgEscape(color), opacity));
  std::string dots;
  for (size_t i = 0; i < n; i += Stride(n, max_points))
    if (std::isfinite(x[i]) && std::isfinite(y[i]))
      absl::StrAppendFormat(&dots, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%g\"/>\n", frame.X(x[i]),
                            frame.Y(y[i]), radius);
  canvas.Raw(dots);
  canvas.CloseGroup();
}

void DrawMarker(SvgCanvas& canvas, double x, double y, const MarkerStyle& style) {
  if (!style.css_class.empty())
    canvas.OpenGroup(absl::StrCat("class=\"", SvgEscape(style.css_class), "\""));
  const double half = style.size / 2;
  // The halo: the same shape in white, 2 px wider, underneath.
  auto draw = [&](bool halo) {
    const Stroke stroke{halo ? "white" : style.color, style.line_width + (halo ? 2 : 0), ""};
    switch (style.shape) {
      case MarkerShape::kCross:
        canvas.Path(absl::StrFormat("M%.1f %.1fh%gM%.1f %.1fv%g", x - half, y, style.size, x,
                                    y - half, style.size),
                    stroke);
        break;
      case MarkerShape::kRing:
        canvas.Circle(x, y, half, "none", &stroke);
        break;
      case MarkerShape::kBox:
        canvas.Rect(x - half, y - half, style.size, style.size, style.color,
                    halo ? &stroke : nullptr);
        break;
      case MarkerShape::kDiamond:
        canvas.Polygon({{x, y - half}, {x + half, y}, {x, y + half}, {x - half, y}}, stroke);
        break;
    }
  };
  if (style.halo) draw(true);
  draw(false);
  if (!style.css_class.empty()) canvas.CloseGroup();
}

void DrawArrow(SvgCanvas& canvas, double x1, double y1, double x2, double y2, const Stroke& stroke,
               double head) {
  const double dx = x2 - x1, dy = y2 - y1, length = std::hypot(dx, dy);
  if (!(length >= 0.5)) {
    if (std::isfinite(length)) canvas.Circle(x2, y2, std::max(1.0, stroke.width), stroke.color);
    return;
  }
  head = std::min(head, 0.6 * length);
  const double ux = dx / length, uy = dy / length, half = 0.45 * head;
  const double bx = x2 - head * ux, by = y2 - head * uy;  // where the head meets the shaft
  canvas.Line(x1, y1, bx, by, stroke);
  canvas.Path(absl::StrFormat("M%.1f,%.1fL%.1f,%.1fL%.1f,%.1fZ", x2, y2, bx - half * uy,
                              by + half * ux, bx + half * uy, by - half * ux),
              Stroke{stroke.color, 1, ""}, stroke.color);
}

double DrawLegend(SvgCanvas& canvas, double x, double y, const std::vector<LegendEntry>& entries,
                  double row, double max_width) {
  const double label_width =
      max_width > 0 ? max_width - 24 : std::numeric_limits<double>::infinity();
  for (const LegendEntry& e : entries) {
    const double mid = y - 4;
    switch (e.swatch) {
      case LegendEntry::Swatch::kLine:
        canvas.Line(x, mid, x + 20, mid, e.line);
        break;
      case LegendEntry::Swatch::kBox:
        canvas.Rect(x + 3, mid - 5, 14, 10, e.color);
        break;
      case LegendEntry::Swatch::kMarker: {
        MarkerStyle plain = e.marker;
        plain.halo = false;
        plain.css_class.clear();
        DrawMarker(canvas, x + 10, mid, plain);
        break;
      }
    }
    y = canvas.WrappedText(x + 24, y, e.label, label_width, {}, row, 4);
  }
  return y;
}

double LegendHeight(const std::vector<LegendEntry>& entries, double font_size, double row,
                    double max_width) {
  const double label_width =
      max_width > 0 ? max_width - 24 : std::numeric_limits<double>::infinity();
  double height = 0;
  for (const LegendEntry& e : entries)
    height += row * WrapText(e.label, font_size, label_width, 4).size();
  return height;
}

ColorRamp::ColorRamp(std::vector<uint32_t> anchors) : anchors_(std::move(anchors)) {
  if (anchors_.empty()) anchors_ = {0x000000, 0xffffff};
  if (anchors_.size() == 1) anchors_.push_back(anchors_.front());
}

ColorRamp ColorRamp::Viridis() {
  return ColorRamp({0x440154, 0x3b528b, 0x21918c, 0x5ec962, 0xfde725});
}

uint32_t ColorRamp::At(double t) const {
  if (!std::isfinite(t)) t = 0;
  t = std::clamp(t, 0.0, 1.0) * (anchors_.size() - 1);
  const int i = std::min(static_cast<int>(t), static_cast<int>(anchors_.size()) - 2);
  const double f = t - i;
  uint32_t out = 0;
  for (int shift : {16, 8, 0}) {
    const double a = (anchors_[i] >> shift) & 0xff, b = (anchors_[i + 1] >> shift) & 0xff;
    out |= static_cast<uint32_t>(std::lround(a + f * (b - a))) << shift;
  }
  return out;
}

void DrawColorBar(SvgCanvas& canvas, const ColorBar& bar, const ColorRamp& ramp) {
  const std::string id = SvgEscape(bar.id);
  canvas.OpenGroup(absl::StrCat("id=\"", id, "\""));
  std::string gradient = absl::StrCat("<defs><linearGradient id=\"", id,
                                      "-ramp\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">");
  const std::vector<uint32_t>& stops = ramp.anchors();
  for (size_t i = 0; i < stops.size(); ++i)
    absl::StrAppendFormat(&gradient, "<stop offset=\"%g\" stop-color=\"%s\"/>",
                          double(i) / (stops.size() - 1), HexColor(stops[i]));
  canvas.Raw(absl::StrCat(gradient, "</linearGradient></defs>\n"));
  if (!bar.title.empty()) canvas.Text(bar.x, bar.y - 12, bar.title);
  const Stroke outline{"#444", 1, ""};
  canvas.Rect(bar.x, bar.y, bar.width, bar.height, absl::StrCat("url(#", id, "-ramp)"), &outline);
  const PlotFrame scale{bar.x, bar.y, bar.width, bar.height, 0, 1, bar.lo, bar.hi};
  canvas.OpenGroup("class=\"bar-ticks\"");
  for (double v : bar.ticks.values) {
    if (!Inside(v, bar.lo, bar.hi)) continue;
    const double y = scale.Y(v);
    canvas.Line(bar.x + bar.width, y, bar.x + bar.width + 4, y, outline);
    canvas.Text(bar.x + bar.width + 7, y + 4, TickLabel(v, bar.ticks.step), {.size = 11});
  }
  canvas.CloseGroup();
  std::string marks;
  for (const auto& [value, tooltip] : bar.marks)
    if (std::isfinite(value) && Inside(value, bar.lo, bar.hi))
      absl::StrAppendFormat(
          &marks,
          "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"white\"><title>%s</title>"
          "</line>\n",
          bar.x + 2, scale.Y(value), bar.x + bar.width - 2, scale.Y(value), SvgEscape(tooltip));
  canvas.Raw(marks);
  canvas.CloseGroup();
}

}  // namespace tactforce::io
