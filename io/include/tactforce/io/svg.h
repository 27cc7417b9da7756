// SVG figures without a plotting library, for every plot of the project (the
// audit's report plots, the experiments' time series, the density picture of
// an inertia fit): a canvas, plot frames with "nice" ticks and axis titles,
// legends, line traces, scatter markers, point markers and colour bars.
// This is the one place for SVG text escaping, tick choice and tick labels.
//
// Coordinates: canvas pixels, x to the right, y DOWN, origin top left. A
// PlotFrame maps data coordinates (y up) into its rectangle. Colours are CSS
// colours ("#3182bd", "black") or 0xRRGGBB numbers through HexColor.
#pragma once

#include <cstdint>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace tactforce::io {

// ---- Text, colours and ticks -------------------------------------------------

// `text` with &, <, >, " and ' as entities: safe as element text and as an
// attribute value.
std::string SvgEscape(std::string_view text);

// "#rrggbb" of 0xRRGGBB.
std::string HexColor(uint32_t rgb);

// The smallest 1, 2 or 5 times a power of ten that is at least `raw`
// (within 1e-12); 1 when `raw` is not positive and finite.
double NiceStep(double raw);

struct Ticks {
  double step = 1;               // distance between ticks, data units
  std::vector<double> values{};  // ascending multiples of step
};

// The multiples of `step` in [lo, hi] (each end included within 1e-9 of the
// span), exact multiples without -0 (k * step, k an integer).
Ticks TicksAt(double lo, double hi, double step);

// TicksAt(lo, hi, NiceStep((hi - lo) / intervals)): a nice step that cuts the
// range into at most `intervals` parts; the step is under 2.5 x the raw one,
// so there are floor(intervals / 2.5) to intervals + 1 ticks.
Ticks NiceTicks(double lo, double hi, int intervals = 5);

// At least three ticks in [lo, hi] (hi > lo, both finite): NiceTicks, with
// the step lowered through 1-2-5 values while fewer than three fall inside.
// An axis with one or two labels does not say its scale.
Ticks AxisTicks(double lo, double hi, int intervals = 5);

// A tick value as text: `value` rounded to a multiple of `step`, "%.6g",
// never "-0" ("0.3", "2000", "-100", "1e+06").
std::string TickLabel(double value, double step);

// The extent of some data, for an axis.
struct Range {
  double lo = std::numeric_limits<double>::infinity();
  double hi = -std::numeric_limits<double>::infinity();

  void Include(double v);  // non-finite values are ignored
  void Include(const std::vector<double>& values);
  // [lo, hi] grown by `pad` x (hi - lo) at both ends; [0, 1] when nothing
  // finite was included, [lo, lo + 1] when all values were equal.
  Range ForAxis(double pad = 0) const;
};

// ---- Canvas -------------------------------------------------------------------

enum class TextAnchor { kStart, kMiddle, kEnd };

// ---- Text extent and layout (estimates: no font metrics without a renderer) ---

// The estimated width (px) of `text` at `size` px sans-serif: 0.6 x size per
// character (UTF-8 code point), a little wider than DejaVu Sans and Helvetica
// average over digits and lower-case letters, so estimated boxes that do not
// overlap do not overlap when rendered.
double TextWidth(std::string_view text, double size);

// A text's box on the canvas (px, y down).
struct TextBox {
  double left = 0, top = 0, right = 0, bottom = 0;
};

// The box of `text` drawn at (x, y) (the baseline) with `size`, `anchor` and
// `vertical` as in TextStyle: 0.8 x size above the baseline to 0.25 x size
// below, TextWidth long (turned about (x, y) when vertical).
TextBox TextBoxOf(double x, double y, std::string_view text, double size, TextAnchor anchor,
                  bool vertical = false);

// The interiors of a and b intersect (by more than `slack` px on both axes).
bool Overlap(const TextBox& a, const TextBox& b, double slack = 0.5);

// `text` in lines of at most `max_width` px at `size` px, broken at spaces;
// at most `max_lines` lines, the last shortened with "\u2026" when the text
// does not fit (a word longer than a line is shortened the same way).
std::vector<std::string> WrapText(std::string_view text, double size, double max_width,
                                  int max_lines = 3);

// Places labels beside points so that no two labels, and no label and a
// blocked box, overlap, inside `bounds`: tries eight positions around the
// point at growing distances and takes the first free one (the first
// candidate when none is).
class LabelPlacer {
 public:
  explicit LabelPlacer(const TextBox& bounds) : bounds_(bounds) {}
  void Block(const TextBox& box) { placed_.push_back(box); }
  // The baseline-start (x, y) of `text` at `size` px near the point (x, y),
  // to draw with TextAnchor::kStart; the label's box is blocked from now on.
  std::pair<double, double> Place(double x, double y, std::string_view text, double size);

 private:
  TextBox bounds_;
  std::vector<TextBox> placed_;
};

struct TextStyle {
  double size = 0;  // px; 0: the canvas's font size
  bool bold = false;
  TextAnchor anchor = TextAnchor::kStart;
  std::string color{};    // empty: black
  bool vertical = false;  // rotated -90 degrees about (x, y), read bottom to top
};

struct Stroke {
  std::string color = "black";
  double width = 1;    // px
  std::string dash{};  // SVG dash array, e.g. "5,4"; empty: solid
};

// An SVG document being written: elements in drawing order (later on top).
// Every text passes through SvgEscape; numbers are written with one decimal.
class SvgCanvas {
 public:
  // A white page of width x height px; `font_size` px sans-serif.
  SvgCanvas(double width, double height, double font_size = 12);

  double width() const { return width_; }
  double height() const { return height_; }
  double font_size() const { return font_size_; }

  // Text with its baseline at y (anchor decides what x is).
  void Text(double x, double y, std::string_view text, const TextStyle& style = {});
  // `text` wrapped (WrapText) to `max_width` px, lines `line_height` px apart
  // (0: 1.3 x the size), the first baseline at y; returns the baseline one
  // line below the last. Titles that fit the canvas, whatever their length.
  double WrappedText(double x, double y, std::string_view text, double max_width,
                     const TextStyle& style = {}, double line_height = 0, int max_lines = 3);
  void Line(double x1, double y1, double x2, double y2, const Stroke& stroke);
  // A rectangle filled with `fill` ("none" for an outline) and, when
  // `outline` is set, stroked; `css_class` (optional) comes first, as
  // <rect class="frame" x=... y=... width=... height=... .../>.
  void Rect(double x, double y, double w, double h, std::string_view fill,
            const Stroke* outline = nullptr, std::string_view css_class = "");
  void Circle(double cx, double cy, double r, std::string_view fill,
              const Stroke* outline = nullptr);
  // An ellipse of semi-axes rx, ry px centred on (cx, cy), its rx axis turned
  // `angle_deg` degrees from +x (clockwise on screen, as SVG's rotate());
  // filled with `fill` ("none" for an outline) and stroked when `outline` is
  // set. A semi-axis of 0 is drawn as a line (SVG would not draw it at all).
  void Ellipse(double cx, double cy, double rx, double ry, double angle_deg, std::string_view fill,
               const Stroke* outline = nullptr);
  // A path (SVG path data `d`), not filled unless `fill` is given.
  void Path(std::string_view d, const Stroke& stroke, std::string_view fill = "none");
  // A closed polygon through the points (x[i], y[i]) px.
  void Polygon(const std::vector<std::pair<double, double>>& points, const Stroke& stroke,
               std::string_view fill = "none");
  // <g> with the given raw attributes (e.g. id="view-1"); groups nest.
  void OpenGroup(std::string_view attributes = "");
  void CloseGroup();
  // Markup the caller has built (and escaped) itself: styles, gradients,
  // large paths.
  void Raw(std::string_view markup);

  // The document (open groups are closed).
  std::string Finish();

 private:
  double width_, height_, font_size_;
  int open_groups_ = 0;
  std::string out_;
};

// ---- Plot frames and axes ---------------------------------------------------------

// A rectangle on the canvas and the data ranges at its edges.
struct PlotFrame {
  double left = 0, top = 0, width = 1, height = 1;  // px
  double x_lo = 0, x_hi = 1;                        // data x at the left and right edges
  double y_lo = 0, y_hi = 1;                        // data y at the bottom and top edges

  double right() const { return left + width; }
  double bottom() const { return top + height; }
  double X(double x) const { return left + (x - x_lo) / (x_hi - x_lo) * width; }       // px
  double Y(double y) const { return bottom() - (y - y_lo) / (y_hi - y_lo) * height; }  // px
};

struct AxisStyle {
  std::string title{};       // centred below the frame (x) or rotated left of it (y); empty: none
  double title_offset = 32;  // px from the frame's edge to the title's baseline
  bool grid = true;          // a light line across the frame at each tick
  bool tick_labels = true;
  double tick_font_size = 0;  // px; 0: the canvas's font size
};

// Grid lines, tick labels and titles of both axes of `frame` (ticks outside
// the frame's range are skipped). Draw it before the data; the frame's
// outline (DrawFrameOutline) after. Tick labels are grouped as
// <g class="x-ticks"> and <g class="y-ticks">; an x label that would touch
// its left neighbour is skipped; the y title moves left of the widest y tick
// label, and the x title below the x tick labels, when title_offset is too
// small for them.
void DrawAxes(SvgCanvas& canvas, const PlotFrame& frame, const Ticks& x_ticks,
              const AxisStyle& x_style, const Ticks& y_ticks, const AxisStyle& y_style);

// The frame's rectangle, unfilled (css_class as in SvgCanvas::Rect).
void DrawFrameOutline(SvgCanvas& canvas, const PlotFrame& frame, const Stroke& stroke,
                      std::string_view css_class = "");

// A vertical rule across the frame at data x (skipped outside the frame's x
// range), with `label` (may be empty) at its top right.
void DrawVerticalRule(SvgCanvas& canvas, const PlotFrame& frame, double x, const Stroke& stroke,
                      std::string_view label = "", std::string_view label_color = "");

// ---- Data -----------------------------------------------------------------------

// A line through the points (x[i], y[i]) of the frame; a non-finite point
// breaks it. Long series are thinned to about `max_points` (every k-th point).
void DrawLineTrace(SvgCanvas& canvas, const PlotFrame& frame, const std::vector<double>& x,
                   const std::vector<double>& y, const Stroke& stroke, size_t max_points = 5000);

// A dot of `radius` px at each finite point, in one group of `color` at
// `opacity`; thinned like DrawLineTrace.
void DrawScatter(SvgCanvas& canvas, const PlotFrame& frame, const std::vector<double>& x,
                 const std::vector<double>& y, std::string_view color, double radius = 1.6,
                 double opacity = 0.6, size_t max_points = 2500);

enum class MarkerShape {
  kCross,    // "+", arms of `size` px
  kRing,     // circle of diameter `size` px, not filled
  kBox,      // filled square of `size` px
  kDiamond,  // a square of diagonal `size` px standing on a corner, not filled
};

struct MarkerStyle {
  MarkerShape shape = MarkerShape::kCross;
  std::string color = "black";
  double size = 14;         // px
  double line_width = 2;    // px
  bool halo = false;        // a white outline underneath, for markers over colour
  std::string css_class{};  // on the marker's <g> when set
};

// One marker centred on (x, y) px.
void DrawMarker(SvgCanvas& canvas, double x, double y, const MarkerStyle& style);

// An arrow from (x1, y1) to (x2, y2) px: the shaft in `stroke` and a filled
// triangular head of length `head` px (at most 0.6 x the arrow's length) in
// the stroke's colour. An arrow shorter than 0.5 px is a dot of the stroke's
// width (a zero vector seen end on).
void DrawArrow(SvgCanvas& canvas, double x1, double y1, double x2, double y2, const Stroke& stroke,
               double head = 8);

// ---- Legends and colour bars ------------------------------------------------------

struct LegendEntry {
  std::string label{};
  enum class Swatch { kLine, kBox, kMarker } swatch = Swatch::kLine;
  Stroke line{};         // kLine: colour, width and dash of the sample line
  std::string color{};   // kBox: fill
  MarkerStyle marker{};  // kMarker (drawn without halo or class)
};

// Entries one under the other: the first label's baseline at y, `row` px
// apart; a 20 px swatch at x, its label at x + 24, wrapped to `max_width` px
// (whole legend, swatch included; 0: no wrapping) with one more row per
// extra line. Returns the baseline below the last entry.
double DrawLegend(SvgCanvas& canvas, double x, double y, const std::vector<LegendEntry>& entries,
                  double row = 16, double max_width = 0);
// The height DrawLegend takes (rows x row) at the canvas font size `font_size`.
double LegendHeight(const std::vector<LegendEntry>& entries, double font_size, double row = 16,
                    double max_width = 0);

// A sequential colour ramp, linear in sRGB between equally spaced anchors.
class ColorRamp {
 public:
  explicit ColorRamp(std::vector<uint32_t> anchors);  // at least two
  // A dark-purple -> blue -> green -> yellow ramp (viridis-like) of five anchors.
  static ColorRamp Viridis();

  uint32_t At(double t) const;  // t clamped to [0, 1]; not finite: 0
  const std::vector<uint32_t>& anchors() const { return anchors_; }

 private:
  std::vector<uint32_t> anchors_;
};

struct ColorBar {
  double x = 0, y = 0, width = 18, height = 200;  // px; `lo` at the bottom
  double lo = 0, hi = 1;
  Ticks ticks{};                  // labelled right of the bar
  std::string title{};            // above the bar
  std::string id = "colour-bar";  // of the bar's <g>; also names its gradient
  // Values marked by a thin white line across the bar, each with a tooltip.
  std::vector<std::pair<double, std::string>> marks{};
};

void DrawColorBar(SvgCanvas& canvas, const ColorBar& bar, const ColorRamp& ramp);

// ---- Stacked time series (the experiments' trace plots) -----------------------------

struct SvgSeries {
  std::string name{};
  std::string color{};  // CSS colour
  bool dashed = false;
  std::vector<double> y{};  // same length as the plot's x
};

struct SvgPanel {
  std::string title{};
  std::string y_label{};
  std::vector<SvgSeries> series{};
};

struct SvgPlot {
  std::string title;
  std::string x_label;
  std::vector<double> x;
  std::vector<SvgPanel> panels;
  // Optional vertical markers (e.g. phase starts) with labels.
  std::vector<std::pair<double, std::string>> markers;
};

// Panels stacked top to bottom sharing the x axis (ticks under the last
// panel), each with its series' legend on the right.
std::string RenderSvg(const SvgPlot& plot, int width = 900, int panel_height = 200);

}  // namespace tactforce::io
