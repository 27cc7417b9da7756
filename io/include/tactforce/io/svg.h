// Minimal SVG line plots (no plotting library): stacked panels sharing the
// time axis, each with several named series.
#pragma once

#include <string>
#include <vector>

namespace tactforce::io {

struct SvgSeries {
  std::string name;
  std::string color;   // CSS colour
  bool dashed = false;
  std::vector<double> y;  // same length as the plot's x
};

struct SvgPanel {
  std::string title;
  std::string y_label;
  std::vector<SvgSeries> series;
};

struct SvgPlot {
  std::string title;
  std::string x_label;
  std::vector<double> x;
  std::vector<SvgPanel> panels;
  // Optional vertical markers (e.g. phase starts) with labels.
  std::vector<std::pair<double, std::string>> markers;
};

std::string RenderSvg(const SvgPlot& plot, int width = 900, int panel_height = 200);

}  // namespace tactforce::io
