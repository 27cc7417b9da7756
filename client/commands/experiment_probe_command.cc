// `tactforce experiment probe`: flags to a ProbeConfig and surfaces, the
// run with a progress bar on stderr, and the output: a per-surface table with
// the paper's median error beside ours, or JSON with every trial.
#include "experiment_probe_command.h"

#include <filesystem>
#include <iostream>
#include <map>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "progress.h"
#include "tactforce/experiment/probe.h"
#include "tactforce/io/json.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

namespace ex = tactforce::experiment;
using io::JsonEscape;
using io::JsonNumber;

constexpr double kPaperMedianError = 0.0056;  // Sundaralingam & Hermans, Sec. V-B

// --object: a built-in name, else a JSON file (a name ending in .json or an existing file).
absl::StatusOr<ex::ProbeObject> ResolveObject(const std::string& spec) {
  if (!absl::EndsWith(spec, ".json") && !std::filesystem::is_regular_file(spec)) {
    absl::StatusOr<ex::ProbeObject> o = ex::FindProbeObject(spec);
    if (!o.ok())
      return absl::InvalidArgumentError(absl::StrCat("--object: ", o.status().message()));
    return o;
  }
  absl::StatusOr<std::string> text = ReadInput(spec, "--object");
  if (!text.ok()) return absl::InvalidArgumentError(text.status().message());
  absl::StatusOr<ex::ProbeObject> o = ex::ProbeObjectFromJson(*text, InputName(spec));
  if (!o.ok()) return absl::InvalidArgumentError(absl::StrCat("--object: ", o.status().message()));
  return o;
}

absl::StatusOr<std::vector<ex::SurfacePair>> Surfaces(const ProbeArgs& a) {
  if (a.mus.empty()) return ex::BuiltInSurfaces();
  std::vector<ex::SurfacePair> out;
  for (double mu : a.mus) out.push_back({absl::StrFormat("mu=%g", mu), mu});
  if (absl::Status s = ex::ValidateSurfaces(out); !s.ok()) return io::PrependPath(s, "--mu");
  return out;
}

absl::StatusOr<ex::ProbeConfig> Config(const ProbeArgs& a) {
  ex::ProbeConfig c;
  TF_ASSIGN_OR_RETURN(c.object, ResolveObject(a.object));
  c.on_table = a.on_table;
  c.seed = a.seed;
  c.force_sigma = a.force_sigma;
  c.force_bias = a.force_bias;
  c.contact_sigma = a.contact_sigma;
  c.hold_scale = a.hold_scale;
  c.admittance_gain = a.admittance_gain;
  c.plan_sigma = a.plan_sigma;
  c.slope.friction.pre_slip = a.pre_slip == "fit" ? estimator::PreSlipForce::kLinearFit
                                                  : estimator::PreSlipForce::kWindowAverage;
  if (absl::Status s = ex::ValidateProbeConfig(c); !s.ok()) {
    const std::string m(s.message());
    const char* flag = absl::StartsWith(m, "force_sigma")     ? "--force-sigma"
                       : absl::StartsWith(m, "force_bias")    ? "--force-bias"
                       : absl::StartsWith(m, "hold_scale")    ? "--hold-scale"
                       : absl::StartsWith(m, "contact_sigma") ? "--contact-sigma"
                       : absl::StartsWith(m, "object")        ? "--object"
                                                              : "experiment probe";
    return absl::InvalidArgumentError(absl::StrCat(flag, ": ", m));
  }
  return c;
}

std::string TrialJson(const ex::ProbeTrialResult& t) {
  return absl::StrCat("{\"surface\":", JsonEscape(t.surface), ",\"trial\":", t.trial,
                      ",\"mu_true\":", JsonNumber(t.mu_true),
                      ",\"mu_slope\":", JsonNumber(t.mu_slope),
                      ",\"mu_estimated\":", t.valid ? JsonNumber(t.mu_estimated) : "null",
                      ",\"error\":", t.valid ? JsonNumber(t.error) : "null",
                      ",\"valid\":", t.valid ? "true" : "false",
                      ",\"invalid_reason\":", t.valid ? "null" : JsonEscape(t.invalid_reason),
                      ",\"object_motion_mm\":", JsonNumber(t.object_motion_mm),
                      ",\"object_rotation_deg\":", JsonNumber(t.object_rotation_deg),
                      ",\"slip_detected\":", t.slip_detected ? "true" : "false",
                      ",\"mesh_triangle\":", t.mesh_triangle,
                      ",\"wall_seconds\":", JsonNumber(t.wall_seconds), "}");
}

std::string SurfaceJson(const ex::SurfaceSummary& s) {
  const bool any = s.valid > 0;
  return absl::StrCat(
      "{\"surface\":", JsonEscape(s.surface), ",\"mu_true\":", JsonNumber(s.mu_true),
      ",\"mu_slope\":", JsonNumber(s.mu_slope),
      ",\"mu_plate_probe\":", s.plate_probe_valid ? JsonNumber(s.mu_plate_probe) : "null",
      ",\"trials\":", s.trials, ",\"valid\":", s.valid,
      ",\"median_estimate\":", any ? JsonNumber(s.median_estimate) : "null",
      ",\"median_signed_error\":", any ? JsonNumber(s.median_signed_error) : "null",
      ",\"median_abs_error\":", any ? JsonNumber(s.median_abs_error) : "null",
      ",\"in_grasp_minus_plate\":",
      any && s.plate_probe_valid ? JsonNumber(s.in_grasp_minus_plate) : "null", "}");
}

std::string ReportJson(const ProbeArgs& a, const ex::ProbeConfig& c, const ex::ProbeReport& r) {
  std::string s = "{\"trials\":[";
  for (size_t i = 0; i < r.trials.size(); ++i)
    absl::StrAppend(&s, i ? "," : "", TrialJson(r.trials[i]));
  const ex::ProbeSummary& m = r.summary;
  const bool any = m.valid > 0;
  absl::StrAppend(&s, "],\"summary\":{\"trials\":", m.trials, ",\"valid\":", m.valid,
                  ",\"slip_detected_valid\":", m.slip_detected_valid,
                  ",\"median_signed_error\":", any ? JsonNumber(m.median_signed_error) : "null",
                  ",\"median_abs_error\":", any ? JsonNumber(m.median_abs_error) : "null",
                  ",\"paper_median_error\":", JsonNumber(kPaperMedianError),
                  ",\"mean_in_grasp_minus_plate\":",
                  any ? JsonNumber(m.mean_in_grasp_minus_plate) : "null", ",\"per_surface\":[");
  for (size_t i = 0; i < m.per_surface.size(); ++i)
    absl::StrAppend(&s, i ? "," : "", SurfaceJson(m.per_surface[i]));
  absl::StrAppend(&s, "]},\"config\":{\"object\":", JsonEscape(c.object.name),
                  ",\"on_table\":", c.on_table ? "true" : "false",
                  ",\"force_sigma\":", JsonNumber(c.force_sigma),
                  ",\"force_bias\":", JsonNumber(c.force_bias),
                  ",\"hold_scale\":", JsonNumber(c.hold_scale),
                  ",\"contact_sigma\":", JsonNumber(c.contact_sigma),
                  ",\"plan_sigma\":", JsonNumber(c.plan_sigma),
                  ",\"admittance_gain\":", JsonNumber(c.admittance_gain),
                  ",\"pre_slip\":", JsonEscape(a.pre_slip), ",\"seed\":", a.seed,
                  ",\"error_convention\":\"mu_slope - mu_estimated\"},\"wall_seconds\":",
                  JsonNumber(r.wall_seconds), "}");
  return s;
}

// "-" when there is no value; 4 decimals, signed or not.
std::string Optional(bool has, double v, bool sign) {
  if (!has) return "-";
  return sign ? absl::StrFormat("%+.4f", v) : absl::StrFormat("%.4f", v);
}

std::string SurfaceRow(const ex::SurfaceSummary& s) {
  const bool any = s.valid > 0;
  return absl::StrFormat(
      "%-24s %7.3f %9.4f %9s %6d/%-3d %9s %10s %12s %16s\n", s.surface, s.mu_true, s.mu_slope,
      Optional(s.plate_probe_valid, s.mu_plate_probe, false), s.valid, s.trials,
      Optional(any, s.median_estimate, false), Optional(any, s.median_signed_error, true),
      Optional(any, s.median_abs_error, false),
      Optional(any && s.plate_probe_valid, s.in_grasp_minus_plate, true));
}

std::string ReportTable(const ProbeArgs& a, const ex::ProbeConfig& c, const ex::ProbeReport& r) {
  std::string out = absl::StrFormat(
      "Friction probed in a grasp: %s (%.3g kg), %s, tactile sigma %g N + bias %g N per axis, hold "
      "scale %g, "
      "%d trials per surface, seed %d\n",
      c.object.name, c.object.mass, c.on_table ? "on a table" : "in the air", c.force_sigma,
      c.force_bias, c.hold_scale, a.trials, a.seed);
  absl::StrAppend(&out, absl::StrFormat("%-24s %7s %9s %9s %10s %9s %10s %12s %16s\n", "surface",
                                        "mu_true", "mu_slope", "mu_plate", "valid", "median mu",
                                        "median err", "median |err|", "in-grasp-plate"));
  for (const ex::SurfaceSummary& s : r.summary.per_surface) absl::StrAppend(&out, SurfaceRow(s));
  const ex::ProbeSummary& m = r.summary;
  const bool any = m.valid > 0;
  absl::StrAppend(&out, absl::StrFormat("pooled: %d/%d valid (slip detected in %d of them); median "
                                        "error %s (paper: %.4f), median |error| %s; "
                                        "mean in-grasp - plate %s\n",
                                        m.valid, m.trials, m.slip_detected_valid,
                                        Optional(any, m.median_signed_error, true),
                                        kPaperMedianError, Optional(any, m.median_abs_error, false),
                                        Optional(any, m.mean_in_grasp_minus_plate, true)));
  // Invalid trials per surface and kind of reason (the text before its first number), with one
  // example.
  std::map<std::string, std::pair<int, std::string>> reasons;
  for (const ex::ProbeTrialResult& t : r.trials) {
    if (t.valid) continue;
    const std::string kind =
        t.invalid_reason.substr(0, t.invalid_reason.find_first_of("0123456789"));
    auto& [n, example] = reasons[absl::StrCat(t.surface, ": ", kind)];
    if (n++ == 0) example = t.invalid_reason;
  }
  for (const auto& [key, v] : reasons)
    absl::StrAppend(&out, absl::StrFormat("  invalid %3d x %s (e.g. %s)\n", v.first,
                                          key.substr(0, key.find(": ")), v.second));
  absl::StrAppend(
      &out,
      absl::StrFormat("error = mu_slope - mu_estimated (the paper's mu_gt - mu); %.1f s wall\n",
                      r.wall_seconds));
  return out;
}

}  // namespace

CLI::App* AddProbeCommand(CLI::App* experiment, ProbeArgs& args) {
  CLI::App* p = experiment->add_subcommand("probe",
                                           "Friction probed inside a grasp: 3 fingertips hold, the "
                                           "4th lowers its normal force until it slips");
  p->add_option("--mu", args.mus,
                "Own surfaces: friction coefficients in [0.1, 1.5] (default: the built-in pairs)")
      ->delimiter(',');
  p->add_option("--object", args.object,
                "Built-in box (box, wood-block, sugar-box, offset-box) or FILE.json "
                "{\"size\":[x,y,z],\"mass\":m,\"com_offset\":[x,y,z]}")
      ->capture_default_str();
  p->add_flag("--on-table", args.on_table,
              "The box rests on a table while it is probed (the paper's Fig. 1)");
  p->add_option("--trials", args.trials, "Seeded trials per surface")
      ->check(Between(1, 10000))
      ->capture_default_str();
  p->add_option("--seed", args.seed, "Seed of the tactile noise, bias and probe position")
      ->capture_default_str();
  p->add_option("--force-sigma", args.force_sigma, "Tactile force noise per axis (N)")
      ->capture_default_str();
  p->add_option("--force-bias", args.force_bias,
                "Std. dev. of the per-trial tactile bias per axis (N)")
      ->capture_default_str();
  p->add_option("--contact-sigma", args.contact_sigma, "Tactile contact-point noise per axis (m)")
      ->capture_default_str();
  p->add_option("--hold-scale", args.hold_scale,
                "Scale of the planned holding forces (0.3: negative control)")
      ->capture_default_str();
  p->add_option("--admittance-gain", args.admittance_gain,
                "Holding fingertips' force admittance per 200 Hz tick (0: impedance only)")
      ->check(Between(0, 1))
      ->capture_default_str();
  p->add_option("--plan-sigma", args.plan_sigma,
                "Normal-force sigma (N) the holding plan is made robust to: its grip margin")
      ->check(Between(0, 10))
      ->capture_default_str();
  p->add_option("--pre-slip", args.pre_slip,
                "window: mean of 5 samples before slip (the paper); fit: line fit (ours)")
      ->check(CLI::IsMember({"window", "fit"}))
      ->capture_default_str();
  AddOutputFlags(p, &args.output, "{\"trials\":[...],\"summary\":{...}}");
  p->add_flag("--no-progress", args.no_progress, "No progress bar on stderr");
  p->footer(
      "Examples:\n"
      "  tactforce experiment probe --trials 10\n"
      "  tactforce experiment probe --mu 0.4,0.8 --object my_box.json --on-table --json\n"
      "  tactforce experiment probe --hold-scale 0.3   # negative control: trials must be invalid");
  args.app = p;
  return p;
}

int RunProbe(const ProbeArgs& a) {
  absl::StatusOr<ex::ProbeConfig> c = Config(a);
  if (!c.ok()) return ReportError(c.status());
  absl::StatusOr<std::vector<ex::SurfacePair>> surfaces = Surfaces(a);
  if (!surfaces.ok()) return ReportError(surfaces.status());
  ProgressBar bar("probe", !a.no_progress);
  absl::StatusOr<ex::ProbeReport> r =
      ex::RunProbeExperiment(*c, *surfaces, a.trials, [&](int done, int total) {
        bar.Update(static_cast<double>(done) / total, absl::StrCat(done, "/", total, " trials"));
      });
  bar.Finish();
  if (!r.ok()) return ReportError(r.status());
  if (a.output.json())
    std::cout << io::IndentJson(ReportJson(a, *c, *r)) << std::flush;
  else
    std::cout << ReportTable(a, *c, *r);
  return kExitOk;
}

}  // namespace tactforce::cli
