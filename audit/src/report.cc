// The audit's outputs (audit.h): report.json through io::JsonWriter, the
// plain-text summary, and three SVG plots drawn with io/svg.h (reading vs
// reference, residual vs reference, residual vs time with the held-out
// split). What to plot is decided here; how to draw it is io's.
#include <algorithm>
#include <cmath>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/audit/audit.h"
#include "tactforce/io/json.h"
#include "tactforce/io/svg.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::audit {
namespace {

void WriteDiagnostics(io::JsonWriter& w, const Diagnostics& d) {
  w.BeginObject();
  w.Field("train_rms", d.train_rms);
  w.Field("heldout_rms", d.heldout_rms);
  w.Field("heldout_rms_force", d.heldout_rms_force);
  w.Key("bias_per_force_bin");
  w.BeginArray();
  for (const auto& b : d.bias_bins) {
    w.BeginObject();
    w.Field("lo", b.lo);
    w.Field("hi", b.hi);
    w.FieldInt("count", b.count);
    w.Field("mean_residual", b.mean_residual);
    w.Field("std_error", b.std_error);
    w.EndObject();
  }
  w.EndArray();
  w.Key("loading_unloading");
  w.BeginObject();
  w.Field("loading_mean", d.loading_mean);
  w.FieldInt("loading_count", d.loading_count);
  w.Field("unloading_mean", d.unloading_mean);
  w.FieldInt("unloading_count", d.unloading_count);
  w.Field("difference", d.unloading_mean - d.loading_mean);
  w.EndObject();
  w.Key("ljung_box");
  w.BeginObject();
  w.FieldInt("lags", d.ljung_box_lags);
  w.Field("q", d.ljung_box_q);
  w.Field("p_value", d.ljung_box_p);
  w.EndObject();
  w.Key("cross_correlation_lag");
  w.BeginObject();
  w.FieldInt("samples", d.xcorr_lag_samples);
  w.Field("seconds", d.xcorr_lag_seconds);
  w.EndObject();
  w.Field("residual_time_slope", d.residual_time_slope);
  w.NumberArray("residual_time_bins", d.residual_time_bins);
  w.EndObject();
}

void WriteMap(io::JsonWriter& w, const std::string& key, const std::map<std::string, double>& m) {
  w.Key(key);
  w.BeginObject();
  for (const auto& [k, v] : m) w.Field(k, v);
  w.EndObject();
}

// "parameters": {"form": ..., numbers..., arrays...} ("form" only for the
// effects with two forms).
void WriteParameters(io::JsonWriter& w, const std::string& form,
                     const std::map<std::string, double>& m,
                     const std::map<std::string, std::vector<double>>& arrays) {
  w.Key("parameters");
  w.BeginObject();
  if (!form.empty()) w.Field("form", form);
  for (const auto& [k, v] : m) w.Field(k, v);
  for (const auto& [k, v] : arrays) w.NumberArray(k, v);
  w.EndObject();
}

void WriteCauses(io::JsonWriter& w, const std::vector<Cause>& causes) {
  w.Key("causes");
  w.BeginArray();
  for (const auto& c : causes) {
    w.BeginObject();
    w.Field("effect", c.effect);
    WriteParameters(w, c.form, c.parameters, c.array_parameters);
    WriteMap(w, "uncertainties", c.uncertainties);
    w.Field("heldout_rms_before", c.heldout_rms_before);
    w.Field("heldout_rms_after", c.heldout_rms_after);
    w.Field("gain", c.gain);
    w.Field("delta_bic", c.delta_bic);
    w.Field("found_by", c.found_by);
    w.NumberArray("blocks", std::vector<double>(c.blocks.begin(), c.blocks.end()));
    w.NumberArray("block_gains", c.block_gains);
    w.EndObject();
  }
  w.EndArray();
}

void WriteClockOffset(io::JsonWriter& w, const AuditReport& r) {
  w.Key("clock_offset_s");
  if (r.clock_offset_s)
    w.Number(*r.clock_offset_s);
  else
    w.Null();
  if (r.clock_offset_s) {
    w.Key("clock_offset");
    w.BeginObject();
    w.Field("mode", r.clock_offset_mode);
    if (r.clock_offset_mode == "estimated") {
      w.Field("cross_correlation_s", r.clock_offset_xcorr_s);
      w.Field("refinement_s", r.clock_offset_refinement_s);
      w.Field("peak_correlation", r.clock_offset_correlation);
      w.Field("note",
              "reading clock minus reference clock; includes any constant sensor delay "
              "(indistinguishable from two "
              "streams)");
    }
    w.EndObject();
  }
}

void WriteCandidates(io::JsonWriter& w, const std::vector<CandidateScore>& candidates) {
  w.Key("candidates");
  w.BeginArray();
  for (const auto& c : candidates) {
    w.BeginObject();
    w.FieldInt("round", c.round);
    w.Field("effect", c.effect);
    WriteParameters(w, c.form, c.parameters, c.array_parameters);
    w.Field("heldout_rms", c.heldout_rms);
    w.Field("bic", c.bic);
    w.FieldBool("accepted", c.accepted);
    w.EndObject();
  }
  w.EndArray();
}

void WriteDownstream(io::JsonWriter& w, const std::optional<DownstreamGain>& downstream) {
  w.Key("downstream");
  if (downstream) {
    w.BeginObject();
    w.FieldInt("grasps", downstream->grasps);
    w.Field("method", downstream->method);
    w.Field("error_nominal", downstream->error_nominal);
    w.Field("error_extended", downstream->error_extended);
    w.Field("gain", downstream->gain);
    w.Field("error_exact_readings", downstream->error_exact_readings);
    w.EndObject();
  } else {
    w.Null();
  }
}

// ---- SVG ------------------------------------------------------------------

struct Series {
  std::string label, color;
  std::vector<double> x, y;
  bool line = false;    // a line through the points; otherwise dots
  double radius = 1.6;  // px, dots
  double opacity = 0.6;
};

// The title, the axis titles and the source file of one plot.
struct PlotText {
  std::string title, xlabel, ylabel, source;
};

// One plot of `series` in drawing order (the data's extent, y padded by 5 %),
// the legend right of the frame, with a dashed "held-out" rule at x = `vline`
// when it is finite.
std::string Plot(const PlotText& text, const std::vector<Series>& series, double vline = NAN) {
  constexpr double kWidth = 860, kHeight = 540, kLeft = 80, kRight = 190, kTop = 58, kBottom = 60;
  io::Range x, y;
  for (const Series& s : series)
    for (size_t i = 0; i < s.x.size() && i < s.y.size(); ++i)
      if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) x.Include(s.x[i]), y.Include(s.y[i]);
  x = x.ForAxis();
  y = y.ForAxis(0.05);
  const io::PlotFrame frame{
      kLeft, kTop, kWidth - kLeft - kRight, kHeight - kTop - kBottom, x.lo, x.hi, y.lo, y.hi};
  io::SvgCanvas canvas(kWidth, kHeight, 12);
  canvas.WrappedText(kLeft, 24, text.title, kWidth - kLeft - 10, {.size = 15, .bold = true}, 18, 1);
  if (!text.source.empty())
    canvas.WrappedText(kLeft, 42, "source: " + text.source, kWidth - kLeft - 10, {.color = "#444"},
                       16, 1);
  io::DrawAxes(canvas, frame, io::AxisTicks(x.lo, x.hi), {.title = text.xlabel, .title_offset = 40},
               io::AxisTicks(y.lo, y.hi), {.title = text.ylabel, .title_offset = 62});
  io::DrawVerticalRule(canvas, frame, vline, io::Stroke{"black", 1, "5,4"}, "held-out");
  std::vector<io::LegendEntry> legend;
  for (const Series& s : series) {
    if (s.line)
      io::DrawLineTrace(canvas, frame, s.x, s.y, io::Stroke{s.color, 1.5, ""});
    else
      io::DrawScatter(canvas, frame, s.x, s.y, s.color, s.radius, s.opacity);
    io::LegendEntry entry{.label = s.label, .line = io::Stroke{s.color, 2, ""}};
    if (!s.line)
      entry.swatch = io::LegendEntry::Swatch::kMarker,
      entry.marker = {
          .shape = io::MarkerShape::kBox, .color = s.color, .size = std::max(4.0, 2.5 * s.radius)};
    legend.push_back(entry);
  }
  io::DrawFrameOutline(canvas, frame, io::Stroke{});
  io::DrawLegend(canvas, frame.right() + 12, kTop + 14, legend, 18, kRight - 20);
  return canvas.Finish();
}

// Numbers in the summary text.
std::string Fmt(double v) { return absl::StrFormat("%.4g", v); }

std::string CauseLine(const Cause& c) {
  std::string p;
  if (!c.form.empty()) p = c.form;
  for (const auto& [k, v] : c.array_parameters) {
    absl::StrAppend(&p, p.empty() ? "" : ", ", k, " = [");
    for (size_t i = 0; i < v.size(); ++i) absl::StrAppend(&p, i ? " " : "", Fmt(v[i]));
    p += "]";
  }
  for (const auto& [k, v] : c.parameters) {
    if (k == "full_scale") continue;
    auto u = c.uncertainties.find(k);
    absl::StrAppend(&p, p.empty() ? "" : ", ", k, " = ", Fmt(v));
    if (u != c.uncertainties.end()) absl::StrAppend(&p, " +/- ", Fmt(u->second));
  }
  return p;
}

// Where a cause was found and which time blocks show it.
std::string BlocksNote(const Cause& c, const std::vector<double>& block_times) {
  if (c.found_by == "taxels") return "; from the per-taxel data";
  if (c.blocks.empty() || block_times.size() < 2) return "";
  std::string b;
  for (int k : c.blocks)
    absl::StrAppendFormat(&b, "%s%d (%.4g-%.4g s)", b.empty() ? "" : ", ", k, block_times[k - 1],
                          block_times[k]);
  return absl::StrCat(c.found_by == "blocked" ? "; found by the blocked hold-out" : "",
                      "; shown in block(s) ", b, " of ", block_times.size() - 1);
}

}  // namespace

std::string AuditReportJson(const AuditReport& r, const std::string& extended_model_path) {
  io::JsonWriter w;
  w.BeginObject();
  w.Field("format", "tactforce.audit_report.v1");
  w.Field("source", r.source);
  w.FieldBool("nominal_adequate", r.nominal_adequate);
  WriteCauses(w, r.causes);
  w.Field("extended_model", extended_model_path);
  w.Field("heldout_rms_before", r.heldout_rms_before);
  w.Field("heldout_rms_after", r.heldout_rms_after);
  w.Field("gain", r.gain);
  w.Field("reading_units", r.reading_units);
  w.FieldInt("n_samples", r.n_samples);
  w.FieldInt("n_train", r.n_train);
  w.FieldInt("n_heldout", r.n_heldout);
  w.FieldInt("skipped_nan_rows", r.skipped_nan_rows);
  w.Field("split_time", r.split_time);
  w.NumberArray("block_times", r.block_times);
  WriteClockOffset(w, r);
  w.Key("nominal_model");
  w.BeginObject();
  w.Field("gain", r.nominal_model.gain);
  w.Field("offset", r.nominal_model.offset);
  w.Field("noise", r.nominal_model.noise);
  w.EndObject();
  if (r.given_model_heldout_rms) w.Field("given_model_heldout_rms", *r.given_model_heldout_rms);
  w.Key("diagnostics");
  w.BeginObject();
  w.Key("nominal");
  WriteDiagnostics(w, r.nominal);
  w.Key("extended");
  WriteDiagnostics(w, r.extended);
  w.EndObject();
  WriteCandidates(w, r.candidates);
  WriteDownstream(w, r.downstream);
  w.Key("notes");
  w.BeginArray();
  for (const auto& n : r.notes) w.String(n);
  w.EndArray();
  w.EndObject();
  return w.str();
}

std::string FormatAuditSummary(const AuditReport& r) {
  std::string s;
  absl::StrAppend(&s, "Sensor model audit of ", r.source, "\n");
  absl::StrAppendFormat(&s, "  %d samples (%d training, %d held out from t = %.4g s)", r.n_samples,
                        r.n_train, r.n_heldout, r.split_time);
  if (r.skipped_nan_rows) absl::StrAppendFormat(&s, ", %d NaN rows skipped", r.skipped_nan_rows);
  s += "\n";
  if (r.clock_offset_s) {
    // Microseconds, also for epoch clocks (1.7e9 s).
    auto sec = [](double v) {
      return std::abs(v) >= 1e5 ? absl::StrFormat("%.6f", v) : absl::StrFormat("%.7g", v);
    };
    if (r.clock_offset_mode == "estimated")
      absl::StrAppendFormat(
          &s,
          "  two streams, clock offset (reading - reference clock) %s s, estimated: "
          "cross-correlation %s s (peak |r| %.3f) + audit refinement %.3g s; a constant sensor "
          "delay is part of it\n",
          sec(*r.clock_offset_s), sec(r.clock_offset_xcorr_s), r.clock_offset_correlation,
          r.clock_offset_refinement_s);
    else
      absl::StrAppendFormat(
          &s, "  two streams, clock offset (reading - reference clock) %s s, as given\n",
          sec(*r.clock_offset_s));
  }
  const auto& nm = r.nominal_model;
  absl::StrAppendFormat(&s, "Nominal model: reading = %.6g * force + %.6g  [%s]\n", nm.gain,
                        nm.offset, r.reading_units);
  const auto& d = r.nominal;
  const double g = std::abs(nm.gain) > 0 ? std::abs(nm.gain) : 1;
  absl::StrAppendFormat(&s, "  held-out RMS %.4g %s (%.4g N); training RMS %.4g\n", d.heldout_rms,
                        r.reading_units, d.heldout_rms / g, d.train_rms);
  if (r.given_model_heldout_rms)
    absl::StrAppendFormat(&s, "  the given model, as given: held-out RMS %.4g\n",
                          *r.given_model_heldout_rms);
  s += "  residual bias per force bin (N):";
  for (const auto& b : d.bias_bins)
    if (b.count) absl::StrAppendFormat(&s, " [%.3g-%.3g] %+.3g", b.lo, b.hi, b.mean_residual);
  s += "\n";
  absl::StrAppendFormat(&s, "  loading %+.4g N (%d) vs unloading %+.4g N (%d)\n", d.loading_mean,
                        d.loading_count, d.unloading_mean, d.unloading_count);
  absl::StrAppendFormat(&s, "  Ljung-Box Q(%d) = %.4g, p = %.3g%s\n", d.ljung_box_lags,
                        d.ljung_box_q, d.ljung_box_p,
                        d.ljung_box_p < 0.01 ? " (residuals autocorrelated)" : "");
  absl::StrAppendFormat(&s,
                        "  cross-correlation lag: %d samples (%.4g s); residual trend %.4g N/s\n",
                        d.xcorr_lag_samples, d.xcorr_lag_seconds, d.residual_time_slope);
  if (r.nominal_adequate) {
    s += "Verdict: the nominal model is adequate (no candidate cause improves the held-out error "
         "enough).\n";
  } else {
    s += "Causes (strongest first):\n";
    int i = 1;
    for (const auto& c : r.causes)
      absl::StrAppendFormat(&s, "  %d. %-12s %s; held-out RMS %.4g -> %.4g (gain %.1f %%)%s\n", i++,
                            c.effect, CauseLine(c), c.heldout_rms_before, c.heldout_rms_after,
                            c.gain, BlocksNote(c, r.block_times));
    absl::StrAppendFormat(
        &s, "Extended model (re-simulated): held-out RMS %.4g -> %.4g, gain %.1f %%\n",
        r.heldout_rms_before, r.heldout_rms_after, r.gain);
  }
  if (r.downstream)
    absl::StrAppendFormat(
        &s,
        "Downstream (%s, %d grasps): force error due to readings %.4g N -> %.4g N, gain %.1f %% "
        "(estimator's own error with exact readings %.4g N)\n",
        r.downstream->method, r.downstream->grasps, r.downstream->error_nominal,
        r.downstream->error_extended, r.downstream->gain, r.downstream->error_exact_readings);
  for (const auto& n : r.notes) absl::StrAppend(&s, "Note: ", n, "\n");
  return s;
}

std::vector<std::string> AuditReportFileNames() {
  return {"report.json",
          "summary.txt",
          "extended_model.json",
          "reading_vs_reference.svg",
          "residual_vs_reference.svg",
          "residual_vs_time.svg"};
}

absl::Status WriteAuditReport(const AuditReport& r, const std::string& dir,
                              const std::string& source) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec)
    return absl::InternalError(absl::StrCat(dir, ": cannot create directory: ", ec.message()));
  const std::string model_path = dir + "/extended_model.json";
  TF_RETURN_IF_ERROR(sim::SaveSensorModel(r.extended_model, model_path));
  auto write = [&](const std::string& name, const std::string& text) {
    return io::WriteTextFile(dir + "/" + name, text);
  };
  TF_RETURN_IF_ERROR(write("report.json", AuditReportJson(r, model_path)));
  TF_RETURN_IF_ERROR(write("summary.txt", FormatAuditSummary(r)));

  const double gn = r.nominal_model.gain != 0 ? r.nominal_model.gain : 1;
  const double ge = r.extended_model.gain != 0 ? r.extended_model.gain : 1;
  std::vector<double> res_n(r.t.size()), res_e(r.t.size());
  for (size_t i = 0; i < r.t.size(); ++i) {
    res_n[i] = (r.reading[i] - r.predicted_nominal[i]) / gn;
    res_e[i] = (r.reading[i] - r.predicted_extended[i]) / ge;
  }
  const std::string ylab = absl::StrCat("reading [", r.reading_units, "]");
  {
    // Nominal is affine: draw it as a line over the sorted reference.
    std::vector<double> xs = {*std::min_element(r.reference.begin(), r.reference.end()),
                              *std::max_element(r.reference.begin(), r.reference.end())};
    std::vector<double> ys = {r.nominal_model.gain * xs[0] + r.nominal_model.offset,
                              r.nominal_model.gain * xs[1] + r.nominal_model.offset};
    // Measured dots large and pale underneath, the model's small and dark on top: both show.
    std::vector<Series> se = {
        {"measured", "#888888", r.reference, r.reading, false, 2.6, 0.45},
        {"extended model", "#e6550d", r.reference, r.predicted_extended, false, 1.1, 0.9},
        {"nominal model", "#3182bd", xs, ys, true}};
    TF_RETURN_IF_ERROR(
        write("reading_vs_reference.svg",
              Plot({"Reading vs reference", "reference force [N]", ylab, source}, se)));
  }
  {
    std::vector<Series> se = {
        {"nominal residual", "#3182bd", r.reference, res_n, false, 2.4, 0.45},
        {"extended residual", "#e6550d", r.reference, res_e, false, 1.2, 0.9}};
    TF_RETURN_IF_ERROR(
        write("residual_vs_reference.svg", Plot({"Residual vs reference (force equivalent)",
                                                 "reference force [N]", "residual [N]", source},
                                                se)));
  }
  {
    std::vector<Series> se = {{"nominal residual", "#3182bd", r.t, res_n, false, 2.4, 0.45},
                              {"extended residual", "#e6550d", r.t, res_e, false, 1.2, 0.9}};
    TF_RETURN_IF_ERROR(write("residual_vs_time.svg", Plot({"Residual vs time (force equivalent)",
                                                           "t [s]", "residual [N]", source},
                                                          se, r.split_time)));
  }
  return absl::OkStatus();
}

}  // namespace tactforce::audit
