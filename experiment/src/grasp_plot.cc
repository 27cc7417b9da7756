// TracePlot: one trial's recorded trace as an SVG figure — per fingertip the
// desired, estimated, raw and true normal forces, then the object's slip and
// rotation (each in a panel of its own unit) against where the hand holds
// it; phase changes as markers.
#include "tactforce/experiment/grasp.h"

#include "absl/strings/str_cat.h"

namespace tactforce::experiment {

io::SvgPlot TracePlot(const TrialResult& trial, const std::vector<std::string>& finger_names,
                      const std::string& title) {
  io::SvgPlot plot;
  plot.title = title;
  plot.x_label = "time (s)";
  for (const TraceSample& s : trial.trace) plot.x.push_back(s.t);
  Phase last = Phase::kClose;
  for (size_t k = 0; k < trial.trace.size(); ++k) {
    const TraceSample& s = trial.trace[k];
    if (k == 0 || s.phase != last) plot.markers.emplace_back(s.t, ToString(s.phase));
    last = s.phase;
  }
  for (size_t i = 0; i < finger_names.size(); ++i) {
    io::SvgPanel panel;
    panel.title = absl::StrCat("fingertip ", finger_names[i], ": normal force");
    panel.y_label = "normal force (N)";
    io::SvgSeries des{"desired", "#000000", true, {}}, est{"estimated", "#1f77b4", false, {}},
        raw{"raw reading", "#ff7f0e", false, {}}, tru{"true (MuJoCo)", "#2ca02c", false, {}};
    for (const TraceSample& s : trial.trace) {
      des.y.push_back(s.desired[i]);
      est.y.push_back(s.estimated[i]);
      raw.y.push_back(s.raw[i]);
      tru.y.push_back(s.truth[i]);
    }
    panel.series = {tru, raw, est, des};
    plot.panels.push_back(std::move(panel));
  }
  // One unit per axis: slip (mm) and rotation (deg) in panels of their own.
  io::SvgPanel slip_panel, rotation_panel;
  slip_panel.title = "object slip against where the hand holds it (lift and hold)";
  slip_panel.y_label = "slip (mm)";
  rotation_panel.title = "object rotation against where the hand holds it (lift and hold)";
  rotation_panel.y_label = "rotation (deg)";
  io::SvgSeries slip{"slip", "#d62728", false, {}}, rot{"rotation", "#9467bd", false, {}};
  for (const TraceSample& s : trial.trace) {
    slip.y.push_back(s.slip * 1e3);
    rot.y.push_back(s.rotation_deg);
  }
  slip_panel.series = {slip};
  rotation_panel.series = {rot};
  plot.panels.push_back(std::move(slip_panel));
  plot.panels.push_back(std::move(rotation_panel));
  return plot;
}

}  // namespace tactforce::experiment
