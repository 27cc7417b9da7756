// RenderSvg (svg.h): stacked panels over one x axis, built from the plot
// elements of svg_plot.cc. Layout: margins of 70 px (left, tick labels and
// the y title) and 150 px (right, the legend), panels kGap px apart.
#include <algorithm>

#include "tactforce/io/svg.h"

namespace tactforce::io {
namespace {

constexpr double kLeft = 70, kRight = 150, kTop = 40, kGap = 40, kBottom = 45;

void DrawPanel(SvgCanvas& canvas, const SvgPlot& plot, size_t index, const PlotFrame& frame) {
  const SvgPanel& panel = plot.panels[index];
  const bool first = index == 0, last = index + 1 == plot.panels.size();
  AxisStyle x_style{.title = last ? plot.x_label : "", .title_offset = 35, .tick_labels = last};
  AxisStyle y_style{.title = panel.y_label, .title_offset = 56};
  DrawAxes(canvas, frame, NiceTicks(frame.x_lo, frame.x_hi, 10), x_style, NiceTicks(frame.y_lo, frame.y_hi, 5),
           y_style);
  for (const auto& [x, label] : plot.markers)
    DrawVerticalRule(canvas, frame, x, Stroke{"#bbb", 1, "2,3"}, first ? label : "", "#777");
  std::vector<LegendEntry> legend;
  for (const SvgSeries& series : panel.series) {
    const Stroke stroke{series.color, 1.3, series.dashed ? "6,3" : ""};
    DrawLineTrace(canvas, frame, plot.x, series.y, stroke);
    legend.push_back({.label = series.name, .line = Stroke{series.color, 2, stroke.dash}});
  }
  DrawFrameOutline(canvas, frame, Stroke{"#888", 1, ""});
  canvas.Text(frame.left + 4, frame.top - 6, panel.title, {.bold = true});
  DrawLegend(canvas, frame.right() + 10, frame.top + 14, legend);
}

}  // namespace

std::string RenderSvg(const SvgPlot& plot, int width, int panel_height) {
  const int n_panels = std::max<int>(1, plot.panels.size());
  const double height = kTop + n_panels * panel_height + (n_panels - 1) * kGap + kBottom;
  SvgCanvas canvas(width, height, 11);
  canvas.Text(kLeft, 22, plot.title, {.size = 14});
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
