// `tactforce load --plot FILE.svg`: the run as a figure, drawn with the
// project's SVG module (tactforce/io/svg.h).
//
//   title   the RPC, the concurrency (or rate), the target; calls, calls/s,
//           p50/p99, errors
//   top     latency histogram of the successful calls: bars over a log
//           latency axis (20 bins per decade, tick labels with units), the
//           p50, p99 and maximum as rules. Each bar is a
//           <g class="bar" data-low-us data-high-us data-count> holding its
//           <rect> and a <title> tooltip, inside <g id="latency-histogram">.
//   bottom  calls per second over time (successful calls in 0.1 s intervals,
//           1 s for runs over 20 s): a line and a point per interval in
//           <g id="qps">; failed calls likewise in <g id="qps-failed"> when
//           there are any.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "load_spec.h"

namespace tactforce::cli {

std::string LoadPlotSvg(const LoadReport& report, const std::string& target);

// Writes LoadPlotSvg to `path` (a temporary name, renamed when complete).
// Errors: InvalidArgument naming --plot.
absl::Status WriteLoadPlot(const LoadReport& report, const std::string& target,
                           const std::string& path);

}  // namespace tactforce::cli
