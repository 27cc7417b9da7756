// RenderSvg (svg.h): stacked panels over one x axis, built from the plot
// elements of svg_plot.cc. Layout: the title, then margins of 70 px (left, tick labels and
// the y title) and 150 px (right, the legend), panels kGap px apart.
#include <algorithm>

#include "tactforce/io/svg.h"

namespace tactforce::io {
namespace {

constexpr double kLeft = 70, kRight = 150, kTop = 54, kGap = 40, kBottom = 45;

// The markers' labels right of their rules inside the top of the frame, each
// one row lower than the last while it would overlap a label already drawn.
void DrawMarkerLabels(SvgCanvas& canvas, const SvgPlot& plot, const PlotFrame& frame) {
  std::vector<TextBox> drawn;
  const double size = canvas.font_size();
  for (const auto& [x, label] : plot.markers) {
    if (label.empty() || !(x >= frame.x_lo && x <= frame.x_hi)) continue;
    const double px = std::min(frame.X(x) + 3, frame.right() - TextWidth(label, size) - 2);
    for (double y = frame.top + size + 2; y < frame.bottom(); y += size + 2) {
      const TextBox box = TextBoxOf(px, y, label, size, TextAnchor::kStart);
      if (std::any_of(drawn.begin(), drawn.end(),
                      [&](const TextBox& b) { return Overlap(box, b); }))
        continue;
      canvas.Text(px, y, label, {.color = "#777"});
      drawn.push_back(box);
      break;
    }
  }
}

void DrawPanel(SvgCanvas& canvas, const SvgPlot& plot, size_t index, const PlotFrame& frame) {
  const SvgPanel& panel = plot.panels[index];
  const bool first = index == 0, last = index + 1 == plot.panels.size();
  AxisStyle x_style{.title = last ? plot.x_label : "", .title_offset = 35, .tick_labels = last};
  AxisStyle y_style{.title = panel.y_label, .title_offset = 56};
  DrawAxes(canvas, frame, AxisTicks(frame.x_lo, frame.x_hi, 10), x_style,
           AxisTicks(frame.y_lo, frame.y_hi, 5), y_style);
  for (const auto& [x, label] : plot.markers)
    DrawVerticalRule(canvas, frame, x, Stroke{"#bbb", 1, "2,3"});
  if (first) DrawMarkerLabels(canvas, plot, frame);
  std::vector<LegendEntry> legend;
  for (const SvgSeries& series : panel.series) {
    const Stroke stroke{series.color, 1.3, series.dashed ? "6,3" : ""};
    DrawLineTrace(canvas, frame, plot.x, series.y, stroke);
    legend.push_back({.label = series.name, .line = Stroke{series.color, 2, stroke.dash}});
  }
  DrawFrameOutline(canvas, frame, Stroke{"#888", 1, ""});
  canvas.Text(frame.left + 4, frame.top - 6, panel.title, {.bold = true});
  DrawLegend(canvas, frame.right() + 10, frame.top + 14, legend, 16, kRight - 14);
}

}  // namespace

std::string RenderSvg(const SvgPlot& plot, int width, int panel_height) {
  const int n_panels = std::max<int>(1, plot.panels.size());
  const double height = kTop + n_panels * panel_height + (n_panels - 1) * kGap + kBottom;
  SvgCanvas canvas(width, height, 11);
  canvas.WrappedText(kLeft, 22, plot.title, width - kLeft - 10, {.size = 14}, 18, 1);
  Range x_range;
  x_range.Include(plot.x);
  x_range = x_range.ForAxis();
  for (size_t p = 0; p < plot.panels.size(); ++p) {
    Range y_range;
    for (const SvgSeries& series : plot.panels[p].series) y_range.Include(series.y);
    y_range = y_range.ForAxis(0.05);
    const PlotFrame frame{.left = kLeft,
                          .top = kTop + p * (panel_height + kGap),
                          .width = width - kLeft - kRight,
                          .height = static_cast<double>(panel_height),
                          .x_lo = x_range.lo,
                          .x_hi = x_range.hi,
                          .y_lo = y_range.lo,
                          .y_hi = y_range.hi};
    DrawPanel(canvas, plot, p, frame);
  }
  return canvas.Finish();
}

}  // namespace tactforce::io
