#include <algorithm>
#include <cmath>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/audit/audit.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/json.h"

namespace tactforce::audit {
namespace {

using io::JsonWriter;

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
void WriteParameters(io::JsonWriter& w, const std::string& form, const std::map<std::string, double>& m,
                     const std::map<std::string, std::vector<double>>& arrays) {
  w.Key("parameters");
  w.BeginObject();
  if (!form.empty()) w.Field("form", form);
  for (const auto& [k, v] : m) w.Field(k, v);
  for (const auto& [k, v] : arrays) w.NumberArray(k, v);
  w.EndObject();
}

// ---- SVG ------------------------------------------------------------------

struct Series {
  std::string label, color;
  std::vector<double> x, y;
  bool line = false;
};

std::string Fmt(double v) { return absl::StrFormat("%.4g", v); }

std::vector<double> Ticks(double lo, double hi) {
  const double span = hi - lo;
  if (!(span > 0)) return {lo};
  const double raw = span / 5;
  const double mag = std::pow(10, std::floor(std::log10(raw)));
  double step = mag;
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * mag >= raw) {
      step = m * mag;
      break;
    }
  std::vector<double> t;
  for (double v = std::ceil(lo / step) * step; v <= hi + 1e-9 * span; v += step) t.push_back(v);
  return t;
}

std::string Plot(const std::string& title, const std::string& xlabel, const std::string& ylabel,
                 const std::vector<Series>& series, double vline = NAN) {
  const double W = 800, H = 520, L = 80, Rm = 20, T = 40, B = 60;
  double x0 = 1e300, x1 = -1e300, y0 = 1e300, y1 = -1e300;
  for (const auto& s : series)
    for (size_t i = 0; i < s.x.size(); ++i) {
      if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) continue;
      x0 = std::min(x0, s.x[i]);
      x1 = std::max(x1, s.x[i]);
      y0 = std::min(y0, s.y[i]);
      y1 = std::max(y1, s.y[i]);
    }
  if (!(x1 > x0)) x1 = x0 + 1;
  if (!(y1 > y0)) y1 = y0 + 1;
  const double py = 0.05 * (y1 - y0);
  y0 -= py;
  y1 += py;
  auto X = [&](double v) { return L + (v - x0) / (x1 - x0) * (W - L - Rm); };
  auto Y = [&](double v) { return H - B - (v - y0) / (y1 - y0) * (H - T - B); };
  std::string s = absl::StrFormat(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%g\" height=\"%g\" viewBox=\"0 0 %g %g\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n",
      W, H, W, H);
  absl::StrAppendFormat(&s, "<text x=\"%g\" y=\"24\" text-anchor=\"middle\" font-size=\"15\">%s</text>\n", W / 2,
                        title);
  absl::StrAppendFormat(&s, "<rect x=\"%g\" y=\"%g\" width=\"%g\" height=\"%g\" fill=\"none\" stroke=\"black\"/>\n",
                        L, T, W - L - Rm, H - T - B);
  for (double v : Ticks(x0, x1)) {
    absl::StrAppendFormat(&s, "<line x1=\"%.1f\" y1=\"%g\" x2=\"%.1f\" y2=\"%g\" stroke=\"#ddd\"/>\n", X(v), T, X(v),
                          H - B);
    absl::StrAppendFormat(&s, "<text x=\"%.1f\" y=\"%g\" text-anchor=\"middle\">%s</text>\n", X(v), H - B + 16,
                          Fmt(v));
  }
  for (double v : Ticks(y0, y1)) {
    absl::StrAppendFormat(&s, "<line x1=\"%g\" y1=\"%.1f\" x2=\"%g\" y2=\"%.1f\" stroke=\"#ddd\"/>\n", L, Y(v),
                          W - Rm, Y(v));
    absl::StrAppendFormat(&s, "<text x=\"%g\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n", L - 6, Y(v) + 4, Fmt(v));
  }
  absl::StrAppendFormat(&s, "<text x=\"%g\" y=\"%g\" text-anchor=\"middle\">%s</text>\n", (L + W - Rm) / 2, H - 20,
                        xlabel);
  absl::StrAppendFormat(&s,
                        "<text x=\"18\" y=\"%g\" text-anchor=\"middle\" transform=\"rotate(-90 18 %g)\">%s</text>\n",
                        (T + H - B) / 2, (T + H - B) / 2, ylabel);
  if (std::isfinite(vline) && vline >= x0 && vline <= x1)
    absl::StrAppendFormat(&s,
                          "<line x1=\"%.1f\" y1=\"%g\" x2=\"%.1f\" y2=\"%g\" stroke=\"black\" "
                          "stroke-dasharray=\"5,4\"/><text x=\"%.1f\" y=\"%g\">held-out</text>\n",
                          X(vline), T, X(vline), H - B, X(vline) + 4, T + 14);
  for (const auto& se : series) {
    const size_t n = se.x.size();
    const size_t stride = std::max<size_t>(1, n / 2500);
    if (se.line) {
      s += "<polyline fill=\"none\" stroke-width=\"1.5\" stroke=\"" + se.color + "\" points=\"";
      for (size_t i = 0; i < n; i += stride) absl::StrAppendFormat(&s, "%.1f,%.1f ", X(se.x[i]), Y(se.y[i]));
      s += "\"/>\n";
    } else {
      s += "<g fill=\"" + se.color + "\" fill-opacity=\"0.6\">\n";
      for (size_t i = 0; i < n; i += stride)
        if (std::isfinite(se.y[i]))
          absl::StrAppendFormat(&s, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"1.6\"/>\n", X(se.x[i]), Y(se.y[i]));
      s += "</g>\n";
    }
  }
  double ly = T + 16;
  for (const auto& se : series) {
    absl::StrAppendFormat(&s, "<rect x=\"%g\" y=\"%g\" width=\"12\" height=\"8\" fill=\"%s\"/>", L + 10, ly - 8,
                          se.color);
    absl::StrAppendFormat(&s, "<text x=\"%g\" y=\"%g\">%s</text>\n", L + 28, ly, se.label);
    ly += 16;
  }
  s += "</svg>\n";
  return s;
}

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

}  // namespace

std::string AuditReportJson(const AuditReport& r, const std::string& extended_model_path) {
  io::JsonWriter w;
  w.BeginObject();
  w.Field("format", "tactforce.audit_report.v1");
  w.Field("source", r.source);
  w.FieldBool("nominal_adequate", r.nominal_adequate);
  w.Key("causes");
  w.BeginArray();
  for (const auto& c : r.causes) {
    w.BeginObject();
    w.Field("effect", c.effect);
    WriteParameters(w, c.form, c.parameters, c.array_parameters);
    WriteMap(w, "uncertainties", c.uncertainties);
    w.Field("heldout_rms_before", c.heldout_rms_before);
    w.Field("heldout_rms_after", c.heldout_rms_after);
    w.Field("gain", c.gain);
    w.Field("delta_bic", c.delta_bic);
    w.EndObject();
  }
  w.EndArray();
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
  w.Key("clock_offset_s");
  if (r.clock_offset_s) w.Number(*r.clock_offset_s);
  else w.Null();
  if (r.clock_offset_s) {
    w.Key("clock_offset");
    w.BeginObject();
    w.Field("mode", r.clock_offset_mode);
    if (r.clock_offset_mode == "estimated") {
      w.Field("cross_correlation_s", r.clock_offset_xcorr_s);
      w.Field("refinement_s", r.clock_offset_refinement_s);
      w.Field("peak_correlation", r.clock_offset_correlation);
      w.Field("note",
              "reading clock minus reference clock; includes any constant sensor delay (indistinguishable from two "
              "streams)");
    }
    w.EndObject();
  }
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
  w.Key("candidates");
  w.BeginArray();
  for (const auto& c : r.candidates) {
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
  w.Key("downstream");
  if (r.downstream) {
    w.BeginObject();
    w.FieldInt("grasps", r.downstream->grasps);
    w.Field("method", r.downstream->method);
    w.Field("error_nominal", r.downstream->error_nominal);
    w.Field("error_extended", r.downstream->error_extended);
    w.Field("gain", r.downstream->gain);
    w.Field("error_exact_readings", r.downstream->error_exact_readings);
    w.EndObject();
  } else {
    w.Null();
  }
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
  absl::StrAppendFormat(&s, "  %d samples (%d training, %d held out from t = %.4g s)", r.n_samples, r.n_train,
                        r.n_heldout, r.split_time);
  if (r.skipped_nan_rows) absl::StrAppendFormat(&s, ", %d NaN rows skipped", r.skipped_nan_rows);
  s += "\n";
  if (r.clock_offset_s) {
    // Microseconds, also for epoch clocks (1.7e9 s).
    auto sec = [](double v) {
      return std::abs(v) >= 1e5 ? absl::StrFormat("%.6f", v) : absl::StrFormat("%.7g", v);
    };
    if (r.clock_offset_mode == "estimated")
      absl::StrAppendFormat(&s,
                            "  two streams, clock offset (reading - reference clock) %s s, estimated: "
                            "cross-correlation %s s (peak |r| %.3f) + audit refinement %.3g s; a constant sensor "
                            "delay is part of it\n",
                            sec(*r.clock_offset_s), sec(r.clock_offset_xcorr_s), r.clock_offset_correlation,
                            r.clock_offset_refinement_s);
    else
      absl::StrAppendFormat(&s, "  two streams, clock offset (reading - reference clock) %s s, as given\n",
                            sec(*r.clock_offset_s));
  }
  const auto& nm = r.nominal_model;
  absl::StrAppendFormat(&s, "Nominal model: reading = %.6g * force + %.6g  [%s]\n", nm.gain, nm.offset,
                        r.reading_units);
  const auto& d = r.nominal;
  const double g = std::abs(nm.gain) > 0 ? std::abs(nm.gain) : 1;
  absl::StrAppendFormat(&s, "  held-out RMS %.4g %s (%.4g N); training RMS %.4g\n", d.heldout_rms, r.reading_units,
                        d.heldout_rms / g, d.train_rms);
  if (r.given_model_heldout_rms)
    absl::StrAppendFormat(&s, "  the given model, as given: held-out RMS %.4g\n", *r.given_model_heldout_rms);
  s += "  residual bias per force bin (N):";
  for (const auto& b : d.bias_bins)
    if (b.count) absl::StrAppendFormat(&s, " [%.3g-%.3g] %+.3g", b.lo, b.hi, b.mean_residual);
  s += "\n";
  absl::StrAppendFormat(&s, "  loading %+.4g N (%d) vs unloading %+.4g N (%d)\n", d.loading_mean, d.loading_count,
                        d.unloading_mean, d.unloading_count);
  absl::StrAppendFormat(&s, "  Ljung-Box Q(%d) = %.4g, p = %.3g%s\n", d.ljung_box_lags, d.ljung_box_q,
                        d.ljung_box_p, d.ljung_box_p < 0.01 ? " (residuals autocorrelated)" : "");
  absl::StrAppendFormat(&s, "  cross-correlation lag: %d samples (%.4g s); residual trend %.4g N/s\n",
                        d.xcorr_lag_samples, d.xcorr_lag_seconds, d.residual_time_slope);
  if (r.nominal_adequate) {
    s += "Verdict: the nominal model is adequate (no candidate cause improves the held-out error enough).\n";
  } else {
    s += "Causes (strongest first):\n";
    int i = 1;
    for (const auto& c : r.causes)
      absl::StrAppendFormat(&s, "  %d. %-12s %s; held-out RMS %.4g -> %.4g (gain %.1f %%)\n", i++, c.effect,
                            CauseLine(c), c.heldout_rms_before, c.heldout_rms_after, c.gain);
    absl::StrAppendFormat(&s, "Extended model (re-simulated): held-out RMS %.4g -> %.4g, gain %.1f %%\n",
                          r.heldout_rms_before, r.heldout_rms_after, r.gain);
  }
  if (r.downstream)
    absl::StrAppendFormat(&s,
                          "Downstream (%s, %d grasps): force error due to readings %.4g N -> %.4g N, gain %.1f %% "
                          "(estimator's own error with exact readings %.4g N)\n",
                          r.downstream->method, r.downstream->grasps, r.downstream->error_nominal,
                          r.downstream->error_extended, r.downstream->gain, r.downstream->error_exact_readings);
  for (const auto& n : r.notes) absl::StrAppend(&s, "Note: ", n, "\n");
  return s;
}

absl::Status WriteAuditReport(const AuditReport& r, const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) return absl::InternalError(absl::StrCat(dir, ": cannot create directory: ", ec.message()));
  const std::string model_path = dir + "/extended_model.json";
  if (auto st = sim::SaveSensorModel(r.extended_model, model_path); !st.ok()) return st;
  auto write = [&](const std::string& name, const std::string& text) {
    return io::WriteTextFile(dir + "/" + name, text);
  };
  if (auto st = write("report.json", AuditReportJson(r, model_path)); !st.ok()) return st;
  if (auto st = write("summary.txt", FormatAuditSummary(r)); !st.ok()) return st;

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
    std::vector<Series> se = {{"measured", "#888888", r.reference, r.reading, false},
                              {"extended model", "#e6550d", r.reference, r.predicted_extended, false},
                              {"nominal model", "#3182bd", xs, ys, true}};
    if (auto st = write("reading_vs_reference.svg",
                        Plot("Reading vs reference", "reference force [N]", ylab, se));
        !st.ok())
      return st;
  }
  {
    std::vector<Series> se = {{"nominal residual", "#3182bd", r.reference, res_n, false},
                              {"extended residual", "#e6550d", r.reference, res_e, false}};
    if (auto st = write("residual_vs_reference.svg",
                        Plot("Residual vs reference (force equivalent)", "reference force [N]", "residual [N]", se));
        !st.ok())
      return st;
  }
  {
    std::vector<Series> se = {{"nominal residual", "#3182bd", r.t, res_n, false},
                              {"extended residual", "#e6550d", r.t, res_e, false}};
    if (auto st = write("residual_vs_time.svg",
                        Plot("Residual vs time (force equivalent)", "t [s]", "residual [N]", se, r.split_time));
        !st.ok())
      return st;
  }
  return absl::OkStatus();
}

}  // namespace tactforce::audit
