#include "tactforce/io/svg.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace tactforce::io {
namespace {

std::string Escape(const std::string& s) {
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

double NiceStep(double span, int target_ticks) {
  const double raw = span / std::max(1, target_ticks);
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) return m * mag;
  return 10 * mag;
}

}  // namespace

std::string RenderSvg(const SvgPlot& plot, int width, int panel_height) {
  const int left = 70, right = 150, top = 40, gap = 40, bottom = 45;
  const int n_panels = std::max<int>(1, plot.panels.size());
  const int height = top + n_panels * panel_height + (n_panels - 1) * gap + bottom;
  const int plot_w = width - left - right;
  double x0 = plot.x.empty() ? 0 : plot.x.front(), x1 = plot.x.empty() ? 1 : plot.x.back();
  if (x1 <= x0) x1 = x0 + 1;
  std::string s = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%d\" height=\"%d\" viewBox=\"0 0 %d %d\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
      width, height, width, height);
  absl::StrAppend(&s, absl::StrFormat("<text x=\"%d\" y=\"22\" font-size=\"14\">%s</text>\n", left,
                                      Escape(plot.title)));
  auto sx = [&](double x) { return left + (x - x0) / (x1 - x0) * plot_w; };
  for (int p = 0; p < static_cast<int>(plot.panels.size()); ++p) {
    const SvgPanel& panel = plot.panels[p];
    const int py = top + p * (panel_height + gap);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const SvgSeries& ser : panel.series)
      for (double v : ser.y)
        if (std::isfinite(v)) lo = std::min(lo, v), hi = std::max(hi, v);
    if (!std::isfinite(lo)) lo = 0, hi = 1;
    if (hi - lo < 1e-9) hi = lo + 1;
    const double pad = 0.05 * (hi - lo);
    lo -= pad;
    hi += pad;
    auto sy = [&](double y) { return py + panel_height - (y - lo) / (hi - lo) * panel_height; };
    absl::StrAppend(&s, absl::StrFormat("<rect x=\"%d\" y=\"%d\" width=\"%d\" height=\"%d\" fill=\"none\" "
                                        "stroke=\"#888\"/>\n",
                                        left, py, plot_w, panel_height));
    absl::StrAppend(&s, absl::StrFormat("<text x=\"%d\" y=\"%d\" font-weight=\"bold\">%s</text>\n", left + 4,
                                        py - 6, Escape(panel.title)));
    absl::StrAppend(&s, absl::StrFormat("<text x=\"14\" y=\"%d\" transform=\"rotate(-90 14 %d)\">%s</text>\n",
                                        py + panel_height / 2 + 20, py + panel_height / 2 + 20,
                                        Escape(panel.y_label)));
    const double ystep = NiceStep(hi - lo, 5);
    for (double v = std::ceil(lo / ystep) * ystep; v <= hi; v += ystep) {
      absl::StrAppend(&s, absl::StrFormat("<line x1=\"%d\" x2=\"%d\" y1=\"%.1f\" y2=\"%.1f\" stroke=\"#eee\"/>"
                                          "<text x=\"%d\" y=\"%.1f\" text-anchor=\"end\">%g</text>\n",
                                          left, left + plot_w, sy(v), sy(v), left - 4, sy(v) + 4,
                                          std::abs(v) < 1e-12 ? 0.0 : v));
    }
    for (const auto& [mx, label] : plot.markers) {
      if (mx < x0 || mx > x1) continue;
      absl::StrAppend(&s, absl::StrFormat("<line x1=\"%.1f\" x2=\"%.1f\" y1=\"%d\" y2=\"%d\" stroke=\"#bbb\" "
                                          "stroke-dasharray=\"2,3\"/>\n",
                                          sx(mx), sx(mx), py, py + panel_height));
      if (p == 0)
        absl::StrAppend(&s, absl::StrFormat("<text x=\"%.1f\" y=\"%d\" fill=\"#777\">%s</text>\n", sx(mx) + 2,
                                            py + 12, Escape(label)));
    }
    int legend_y = py + 14;
    for (const SvgSeries& ser : panel.series) {
      std::string path;
      bool pen = false;
      for (size_t i = 0; i < ser.y.size() && i < plot.x.size(); ++i) {
        if (!std::isfinite(ser.y[i])) {
          pen = false;
          continue;
        }
        absl::StrAppend(&path, pen ? "L" : "M", absl::StrFormat("%.1f,%.1f", sx(plot.x[i]), sy(ser.y[i])));
        pen = true;
      }
      absl::StrAppend(&s, absl::StrFormat("<path d=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"1.3\"%s/>\n",
                                          path, ser.color, ser.dashed ? " stroke-dasharray=\"6,3\"" : ""));
      absl::StrAppend(&s, absl::StrFormat("<line x1=\"%d\" x2=\"%d\" y1=\"%d\" y2=\"%d\" stroke=\"%s\" "
                                          "stroke-width=\"2\"%s/><text x=\"%d\" y=\"%d\">%s</text>\n",
                                          left + plot_w + 10, left + plot_w + 30, legend_y - 4, legend_y - 4,
                                          ser.color, ser.dashed ? " stroke-dasharray=\"6,3\"" : "",
                                          left + plot_w + 34, legend_y, Escape(ser.name)));
      legend_y += 16;
    }
    if (p + 1 == static_cast<int>(plot.panels.size())) {
      const double xstep = NiceStep(x1 - x0, 10);
      for (double v = std::ceil(x0 / xstep) * xstep; v <= x1 + 1e-9; v += xstep)
        absl::StrAppend(&s, absl::StrFormat("<text x=\"%.1f\" y=\"%d\" text-anchor=\"middle\">%g</text>\n", sx(v),
                                            py + panel_height + 15, v));
      absl::StrAppend(&s, absl::StrFormat("<text x=\"%d\" y=\"%d\" text-anchor=\"middle\">%s</text>\n",
                                          left + plot_w / 2, py + panel_height + 35, Escape(plot.x_label)));
    }
  }
  absl::StrAppend(&s, "</svg>\n");
  return s;
}

}  // namespace tactforce::io
