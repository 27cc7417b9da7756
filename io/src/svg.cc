// The SVG basics of svg.h: escaping, colours, the one tick algorithm (1-2-5
// steps, ticks as integer multiples of the step so that labels carry no
// rounding noise), data ranges and the canvas that writes the elements.
#include <algorithm>
#include <cmath>
#include <numbers>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/svg.h"

namespace tactforce::io {
namespace {

std::string StrokeAttributes(const Stroke& stroke) {
  std::string s = absl::StrCat(" stroke=\"", SvgEscape(stroke.color), "\"");
  if (stroke.width != 1) absl::StrAppendFormat(&s, " stroke-width=\"%g\"", stroke.width);
  if (!stroke.dash.empty())
    absl::StrAppend(&s, " stroke-dasharray=\"", SvgEscape(stroke.dash), "\"");
  return s;
}

}  // namespace

std::string SvgEscape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string HexColor(uint32_t rgb) { return absl::StrFormat("#%06x", rgb & 0xffffff); }

double NiceStep(double raw) {
  if (!(raw > 0) || !std::isfinite(raw)) return 1.0;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0})
    if (m * magnitude >= raw * (1 - 1e-12)) return m * magnitude;
  return 10 * magnitude;
}

Ticks TicksAt(double lo, double hi, double step) {
  Ticks t;
  t.step = step > 0 && std::isfinite(step) ? step : 1.0;
  if (!std::isfinite(lo) || !std::isfinite(hi) || hi < lo) return t;
  const double slack = 1e-9 * std::max(hi - lo, t.step);
  const double first = std::ceil((lo - slack) / t.step), last = std::floor((hi + slack) / t.step);
  if (last - first > 1e4)
    return t;  // a step far too small for the range: no ticks rather than millions
  for (double k = first; k <= last; ++k) t.values.push_back(k == 0 ? 0.0 : k * t.step);
  return t;
}

Ticks NiceTicks(double lo, double hi, int intervals) {
  return TicksAt(lo, hi, NiceStep((hi - lo) / std::max(1, intervals)));
}

Ticks AxisTicks(double lo, double hi, int intervals) {
  Ticks t = NiceTicks(lo, hi, intervals);
  if (!(hi > lo) || !std::isfinite(hi - lo)) return t;
  // The next lower 1-2-5 step (5 -> 2 -> 1 -> 0.5); a step under a third of the span gives three
  // ticks.
  for (int round = 0; round < 8 && t.values.size() < 3; ++round) {
    const double magnitude = std::pow(10.0, std::floor(std::log10(t.step) + 1e-9));
    const double mantissa = std::round(t.step / magnitude);
    t = TicksAt(lo, hi,
                mantissa >= 5   ? 2 * magnitude
                : mantissa >= 2 ? magnitude
                                : 0.5 * magnitude);
  }
  return t;
}

std::string TickLabel(double value, double step) {
  if (step > 0 && std::isfinite(step)) value = std::round(value / step) * step;
  if (std::abs(value) < 1e-9 * step) value = 0;
  return absl::StrFormat("%.6g", value);
}

void Range::Include(double v) {
  if (!std::isfinite(v)) return;
  lo = std::min(lo, v);
  hi = std::max(hi, v);
}

void Range::Include(const std::vector<double>& values) {
  for (double v : values) Include(v);
}

Range Range::ForAxis(double pad) const {
  Range r = *this;
  if (!(r.lo <= r.hi)) r.lo = 0, r.hi = 1;
  if (!(r.hi > r.lo)) r.hi = r.lo + 1;
  const double grow = pad * (r.hi - r.lo);
  r.lo -= grow;
  r.hi += grow;
  return r;
}

SvgCanvas::SvgCanvas(double width, double height, double font_size)
    : width_(width), height_(height), font_size_(font_size) {
  out_ = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" height=\"%g\" viewBox=\"0 0 %g %g\" "
      "font-family=\"sans-serif\" font-size=\"%g\">\n<rect width=\"100%%\" height=\"100%%\" "
      "fill=\"white\"/>\n",
      width, height, width, height, font_size);
}

void SvgCanvas::Text(double x, double y, std::string_view text, const TextStyle& style) {
  absl::StrAppendFormat(&out_, "<text x=\"%.1f\" y=\"%.1f\"", x, y);
  if (style.anchor == TextAnchor::kMiddle) out_ += " text-anchor=\"middle\"";
  if (style.anchor == TextAnchor::kEnd) out_ += " text-anchor=\"end\"";
  if (style.size > 0 && style.size != font_size_)
    absl::StrAppendFormat(&out_, " font-size=\"%g\"", style.size);
  if (style.bold) out_ += " font-weight=\"bold\"";
  if (!style.color.empty()) absl::StrAppend(&out_, " fill=\"", SvgEscape(style.color), "\"");
  if (style.vertical) absl::StrAppendFormat(&out_, " transform=\"rotate(-90 %.1f %.1f)\"", x, y);
  absl::StrAppend(&out_, ">", SvgEscape(text), "</text>\n");
}

void SvgCanvas::Line(double x1, double y1, double x2, double y2, const Stroke& stroke) {
  absl::StrAppendFormat(&out_, "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\"%s/>\n", x1,
                        y1, x2, y2, StrokeAttributes(stroke));
}

void SvgCanvas::Rect(double x, double y, double w, double h, std::string_view fill,
                     const Stroke* outline, std::string_view css_class) {
  out_ += "<rect";
  if (!css_class.empty()) absl::StrAppend(&out_, " class=\"", SvgEscape(css_class), "\"");
  absl::StrAppendFormat(
      &out_, " x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"%s\"%s/>\n", x, y, w, h,
      SvgEscape(fill), outline != nullptr ? StrokeAttributes(*outline) : "");
}

void SvgCanvas::Circle(double cx, double cy, double r, std::string_view fill,
                       const Stroke* outline) {
  absl::StrAppendFormat(&out_, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%g\" fill=\"%s\"%s/>\n", cx, cy,
                        r, SvgEscape(fill), outline != nullptr ? StrokeAttributes(*outline) : "");
}

void SvgCanvas::Ellipse(double cx, double cy, double rx, double ry, double angle_deg,
                        std::string_view fill, const Stroke* outline) {
  rx = std::abs(rx), ry = std::abs(ry);
  if (rx == 0 || ry == 0) {  // a degenerate ellipse is the segment of its longer axis
    const double r = std::max(rx, ry),
                 a = (rx > 0 ? angle_deg : angle_deg + 90) * std::numbers::pi / 180;
    const Stroke fallback{std::string(fill == "none" ? "black" : fill), 1, ""};
    Line(cx - r * std::cos(a), cy - r * std::sin(a), cx + r * std::cos(a), cy + r * std::sin(a),
         outline != nullptr ? *outline : fallback);
    return;
  }
  absl::StrAppendFormat(&out_, "<ellipse cx=\"%.1f\" cy=\"%.1f\" rx=\"%.2f\" ry=\"%.2f\"", cx, cy,
                        rx, ry);
  if (angle_deg != 0)
    absl::StrAppendFormat(&out_, " transform=\"rotate(%.2f %.1f %.1f)\"", angle_deg, cx, cy);
  absl::StrAppendFormat(&out_, " fill=\"%s\"%s/>\n", SvgEscape(fill),
                        outline != nullptr ? StrokeAttributes(*outline) : "");
}

void SvgCanvas::Polygon(const std::vector<std::pair<double, double>>& points, const Stroke& stroke,
                        std::string_view fill) {
  if (points.empty()) return;
  std::string d;
  for (size_t i = 0; i < points.size(); ++i)
    absl::StrAppendFormat(&d, "%s%.1f,%.1f", i == 0 ? "M" : "L", points[i].first, points[i].second);
  Path(d + "Z", stroke, fill);
}

void SvgCanvas::Path(std::string_view d, const Stroke& stroke, std::string_view fill) {
  absl::StrAppend(&out_, "<path d=\"", SvgEscape(d), "\" fill=\"", SvgEscape(fill), "\"",
                  StrokeAttributes(stroke), "/>\n");
}

void SvgCanvas::OpenGroup(std::string_view attributes) {
  absl::StrAppend(&out_, attributes.empty() ? "<g" : "<g ", std::string(attributes), ">\n");
  ++open_groups_;
}

void SvgCanvas::CloseGroup() {
  if (open_groups_ == 0) return;
  out_ += "</g>\n";
  --open_groups_;
}

void SvgCanvas::Raw(std::string_view markup) { out_.append(markup); }

std::string SvgCanvas::Finish() {
  while (open_groups_ > 0) CloseGroup();
  return absl::StrCat(out_, "</svg>\n");
}

}  // namespace tactforce::io
