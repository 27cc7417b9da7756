// The SVG of a load run (load_plot.h): title lines, the latency histogram
// on a log axis, calls per second over time. Layout: 80 px left margin (tick
// labels, y titles), 160 px right margin (legends), two frames one above the
// other.
#include "load_plot.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/io/svg.h"
#include "tactforce/io/text_file.h"

namespace tactforce::cli {
namespace {

constexpr double kWidth = 900, kLeft = 80, kRight = 160;
constexpr double kHistogramTop = 80, kHistogramHeight = 230;
constexpr double kRateTop = 385, kRateHeight = 200, kHeight = 640;
constexpr double kLongRunS = 20;  // longer runs: calls/s per second, not per 0.1 s

const char kBarColor[] = "#3182bd";
const char kOkColor[] = "#08519c";
const char kFailedColor[] = "#d62728";

// "850 µs", "1.2 ms", "3 s".
std::string DurationLabel(double us) {
  if (us < 1e3) return absl::StrFormat("%.3g µs", us);
  if (us < 1e6) return absl::StrFormat("%.3g ms", us * 1e-3);
  return absl::StrFormat("%.3g s", us * 1e-6);
}

std::string Title(const LoadReport& r) {
  std::string load = r.mode == "open" ? absl::StrFormat("rate %g calls/s, at most %d in flight",
                                                        r.rate, r.concurrency)
                                      : absl::StrFormat("concurrency %d", r.concurrency);
  return absl::StrFormat("tactforce load --rpc %s: %s (%s loop, %s API)", r.rpc, load, r.mode,
                         r.engine);
}

std::string Subtitle(const LoadReport& r, const std::string& target) {
  std::string errors;
  for (const auto& [code, count] : r.errors) absl::StrAppend(&errors, " ", code, "=", count);
  return absl::StrFormat(
      "%s: %d calls (%d ok) in %.2f s, %.1f calls/s; p50 %s, p99 %s; errors:%s%s", target,
      r.requests, r.ok, r.duration_s, r.qps, DurationLabel(r.p50_us), DurationLabel(r.p99_us),
      errors.empty() ? " none" : errors, r.interrupted ? " (interrupted)" : "");
}

// Decade ticks (with 2x and 5x when the axis spans at most two decades) of a
// log10(µs) axis, labelled by hand: DrawAxes would print the exponents.
void DrawLogLatencyTicks(io::SvgCanvas& canvas, const io::PlotFrame& frame) {
  const bool fine = frame.x_hi - frame.x_lo <= 2.0 + 1e-9;
  canvas.OpenGroup("class=\"x-ticks\"");
  for (int k = static_cast<int>(std::floor(frame.x_lo)); k <= frame.x_hi; ++k) {
    for (double m : {1.0, 2.0, 5.0}) {
      if (m != 1.0 && !fine) continue;
      const double x = k + std::log10(m);
      if (x < frame.x_lo - 1e-9 || x > frame.x_hi + 1e-9) continue;
      const double px = frame.X(x);
      canvas.Line(px, frame.top, px, frame.bottom(),
                  io::Stroke{m == 1.0 ? "#d0d0d0" : "#eeeeee", 1, ""});
      canvas.Text(px, frame.bottom() + canvas.font_size() + 5, DurationLabel(std::pow(10.0, x)),
                  {.anchor = io::TextAnchor::kMiddle});
    }
  }
  canvas.CloseGroup();
}

// One bar per bin with calls, each a group carrying its numbers.
void DrawLatencyBars(io::SvgCanvas& canvas, const io::PlotFrame& frame,
                     const std::vector<LatencyHistogram::Bin>& bins) {
  canvas.OpenGroup("id=\"latency-histogram\"");
  for (const LatencyHistogram::Bin& bin : bins) {
    if (bin.count == 0) continue;
    const double low_us = bin.low_ns * 1e-3, high_us = bin.high_ns * 1e-3;
    const double x0 = frame.X(std::log10(low_us)), x1 = frame.X(std::log10(high_us));
    const double y = frame.Y(static_cast<double>(bin.count));
    canvas.OpenGroup(absl::StrFormat(
        "class=\"bar\" data-low-us=\"%.6g\" data-high-us=\"%.6g\" data-count=\"%d\"", low_us,
        high_us, bin.count));
    canvas.Rect(x0 + 0.5, y, std::max(x1 - x0 - 1.0, 0.5), frame.bottom() - y, kBarColor);
    canvas.Raw(
        absl::StrCat("<title>",
                     io::SvgEscape(absl::StrFormat("%s to %s: %d calls", DurationLabel(low_us),
                                                   DurationLabel(high_us), bin.count)),
                     "</title>\n"));
    canvas.CloseGroup();
  }
  canvas.CloseGroup();
}

void DrawHistogramPanel(io::SvgCanvas& canvas, const LoadReport& r) {
  const std::vector<LatencyHistogram::Bin>& bins = r.latency_bins;
  int64_t most = 1;
  for (const LatencyHistogram::Bin& bin : bins) most = std::max(most, bin.count);
  io::PlotFrame frame{.left = kLeft,
                      .top = kHistogramTop,
                      .width = kWidth - kLeft - kRight,
                      .height = kHistogramHeight,
                      .x_lo = 0,
                      .x_hi = 3,
                      .y_lo = 0,
                      .y_hi = most * 1.08};
  if (!bins.empty()) {
    frame.x_lo = std::floor(std::log10(bins.front().low_ns * 1e-3) + 1e-9);
    frame.x_hi = std::max(frame.x_lo + 1, std::ceil(std::log10(bins.back().high_ns * 1e-3) - 1e-9));
  }
  const io::AxisStyle x_style{.title = "latency of a successful call (log scale)",
                              .title_offset = 34,
                              .grid = false,
                              .tick_labels = false};
  const io::AxisStyle y_style{
      .title = absl::StrFormat("calls per 1/%d decade", kLatencyBinsPerDecade), .title_offset = 56};
  io::DrawAxes(canvas, frame, io::Ticks{}, x_style, io::AxisTicks(0, frame.y_hi, 5), y_style);
  DrawLogLatencyTicks(canvas, frame);
  DrawLatencyBars(canvas, frame, bins);
  std::vector<io::LegendEntry> legend;
  if (bins.empty()) {
    canvas.Text(frame.left + frame.width / 2, frame.top + frame.height / 2, "no successful calls",
                {.anchor = io::TextAnchor::kMiddle});
  } else {
    const io::Stroke p50{"#e6550d", 1.5, "5,3"}, p99{kFailedColor, 1.5, ""},
        top{"#555555", 1, "2,2"};
    io::DrawVerticalRule(canvas, frame, std::log10(std::max(r.p50_us, 1e-3)), p50);
    io::DrawVerticalRule(canvas, frame, std::log10(std::max(r.p99_us, 1e-3)), p99);
    io::DrawVerticalRule(canvas, frame, std::log10(std::max(r.max_us, 1e-3)), top);
    legend = {{.label = "p50 " + DurationLabel(r.p50_us), .line = p50},
              {.label = "p99 " + DurationLabel(r.p99_us), .line = p99},
              {.label = "max " + DurationLabel(r.max_us), .line = top}};
  }
  io::DrawFrameOutline(canvas, frame, io::Stroke{"#888888", 1, ""});
  canvas.Text(frame.left + 4, frame.top - 8, "Latency histogram", {.bold = true});
  io::DrawLegend(canvas, frame.right() + 12, frame.top + 14, legend, 16, kRight - 20);
}

// Calls per second in intervals of the timeline (grouped to 1 s for long
// runs); x at the middle of each interval, the last, partial one divided by
// its own length (dropped when under half an interval).
struct Rates {
  double interval_s = 0;
  std::vector<double> t, ok, failed;
};

Rates CallsPerSecond(const LoadReport& r) {
  const CompletionCounts& c = r.timeline;
  Rates rates;
  if (c.interval_s <= 0 || c.ok.empty()) return rates;
  const size_t group =
      r.duration_s > kLongRunS ? static_cast<size_t>(std::lround(1.0 / c.interval_s)) : 1;
  rates.interval_s = c.interval_s * group;
  for (size_t first = 0; first < c.ok.size(); first += group) {
    const double start = first * c.interval_s;
    const double end = std::min(start + rates.interval_s, std::max(r.duration_s, start));
    const double length = end - start;
    if (length < 0.5 * rates.interval_s && !rates.t.empty()) break;
    int64_t ok = 0, failed = 0;
    for (size_t i = first; i < std::min(first + group, c.ok.size()); ++i) {
      ok += c.ok[i];
      failed += c.failed[i];
    }
    const double seconds = std::max(length, 1e-3);
    rates.t.push_back(0.5 * (start + end));
    rates.ok.push_back(ok / seconds);
    rates.failed.push_back(failed / seconds);
  }
  return rates;
}

void DrawRateSeries(io::SvgCanvas& canvas, const io::PlotFrame& frame, const std::vector<double>& t,
                    const std::vector<double>& y, const char* id, const char* color) {
  canvas.OpenGroup(absl::StrCat("id=\"", id, "\""));
  io::DrawLineTrace(canvas, frame, t, y, io::Stroke{color, 1.5, ""});
  io::DrawScatter(canvas, frame, t, y, color, 2.2, 0.9);
  canvas.CloseGroup();
}

void DrawRatePanel(io::SvgCanvas& canvas, const LoadReport& r) {
  const Rates rates = CallsPerSecond(r);
  const bool any_failed = r.ok < r.requests;
  io::Range y_range;
  y_range.Include(0.0);
  y_range.Include(rates.ok);
  if (any_failed) y_range.Include(rates.failed);
  const double y_hi = std::max(y_range.hi, 1.0) * 1.08;
  const double x_hi = std::max(r.duration_s, 1e-3);
  const io::PlotFrame frame{.left = kLeft,
                            .top = kRateTop,
                            .width = kWidth - kLeft - kRight,
                            .height = kRateHeight,
                            .x_lo = 0,
                            .x_hi = x_hi,
                            .y_lo = 0,
                            .y_hi = y_hi};
  const io::AxisStyle x_style{.title = "time since the first call [s]", .title_offset = 34};
  const io::AxisStyle y_style{.title = "calls/s", .title_offset = 56};
  io::DrawAxes(canvas, frame, io::AxisTicks(0, x_hi, 10), x_style, io::AxisTicks(0, y_hi, 5),
               y_style);
  DrawRateSeries(canvas, frame, rates.t, rates.ok, "qps", kOkColor);
  std::vector<io::LegendEntry> legend = {
      {.label = absl::StrFormat("ok (mean %.1f/s)", r.qps), .line = io::Stroke{kOkColor, 2, ""}}};
  if (any_failed) {
    DrawRateSeries(canvas, frame, rates.t, rates.failed, "qps-failed", kFailedColor);
    legend.push_back({.label = "failed", .line = io::Stroke{kFailedColor, 2, ""}});
  }
  io::DrawFrameOutline(canvas, frame, io::Stroke{"#888888", 1, ""});
  canvas.Text(frame.left + 4, frame.top - 8,
              absl::StrFormat("Calls per second (per %g s)", rates.interval_s), {.bold = true});
  io::DrawLegend(canvas, frame.right() + 12, frame.top + 14, legend, 16, kRight - 20);
}

}  // namespace

std::string LoadPlotSvg(const LoadReport& report, const std::string& target) {
  io::SvgCanvas canvas(kWidth, kHeight, 11);
  canvas.WrappedText(kLeft, 24, Title(report), kWidth - kLeft - 10, {.size = 15, .bold = true}, 18,
                     1);
  canvas.WrappedText(kLeft, 44, Subtitle(report, target), kWidth - kLeft - 10,
                     {.size = 12, .color = "#444444"}, 14, 2);
  DrawHistogramPanel(canvas, report);
  DrawRatePanel(canvas, report);
  return canvas.Finish();
}

absl::Status WriteLoadPlot(const LoadReport& report, const std::string& target,
                           const std::string& path) {
  absl::Status written = io::WriteTextFile(path, LoadPlotSvg(report, target));
  if (!written.ok()) {
    return io::PrependPath(written, "--plot");
  }
  return absl::OkStatus();
}
}  // namespace tactforce::cli
