// `tactforce experiment inhand`: flags to an InHandConfig (library errors
// are mapped to the flag that set the field), the run with a progress bar,
// the files, a summary table or JSON, and with --fit every inertia method on
// the log against the truth.
#include "experiment_inhand_command.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "absl/strings/match.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_split.h"
#include "progress.h"
#include "tactforce/io/json.h"
#include "tactforce/experiment/inhand.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

namespace ex = tactforce::experiment;

const std::vector<std::string> kRunFiles = {"inertia.csv", "truth.json", "events.csv",
                                            "truth_log.csv", "mesh.obj"};

std::string Num(double v) { return std::isfinite(v) ? absl::StrFormat("%.6g", v) : "null"; }

// A library message "field: ..." with the flag that set the field.
absl::Status FlagError(const absl::Status& s, const std::string& object_flag_value) {
  const std::string m(s.message());
  const std::pair<const char*, const char*> map[] = {{"rate", "--rate"},
                                                     {"duration", "--duration"},
                                                     {"force_model", "--force-model"},
                                                     {"tracker", "--tracker"},
                                                     {"breaks", "--break"},
                                                     {"support_fraction", "--support-fraction"},
                                                     {"object", "--object"}};
  for (const auto& [field, flag] : map)
    if (absl::StartsWith(m, field)) return absl::InvalidArgumentError(absl::StrCat(flag, ": ", m));
  if (absl::EndsWith(object_flag_value, ".json"))
    return absl::InvalidArgumentError(absl::StrCat("--object: ", m));
  return s;
}

absl::Status ParseBreaks(const std::vector<std::string>& specs, ex::InHandConfig* c) {
  for (const std::string& spec : specs) {
    const std::vector<std::string> parts = absl::StrSplit(spec, ':');
    ex::ContactBreak b;
    if (parts.size() != 3 || !absl::SimpleAtoi(parts[0], &b.contact) ||
        !absl::SimpleAtod(parts[1], &b.start) || !absl::SimpleAtod(parts[2], &b.duration))
      return absl::InvalidArgumentError(
          absl::StrCat("--break: '", spec, "': expected CONTACT:START:DURATION (e.g. 2:4.0:0.5)"));
    c->breaks.push_back(b);
  }
  return absl::OkStatus();
}

absl::StatusOr<ex::InHandConfig> ConfigFromFlags(const InHandArgs& a) {
  ex::InHandConfig c;
  if (absl::EndsWith(a.object, ".json")) {
    absl::StatusOr<ex::InHandObject> o = ex::ReadInHandObjectFile(a.object);
    if (!o.ok())
      return absl::InvalidArgumentError(absl::StrCat("--object: ", o.status().message()));
    c.custom = *o;
  } else {
    c.object = a.object;
  }
  absl::StatusOr<ex::Tracker> t = ex::ParseTracker(a.tracker);
  if (!t.ok()) return absl::InvalidArgumentError(absl::StrCat("--", t.status().message()));
  c.tracker = *t;
  c.duration = a.duration;
  c.rate = a.rate;
  c.seed = a.seed;
  c.force_model = a.force_model;
  c.ideal_forces = a.ideal_forces;
  c.ideal_tracking = a.ideal_tracking;
  c.support_fraction = a.support_fraction;
  TF_RETURN_IF_ERROR(ParseBreaks(a.breaks, &c));
  if (absl::Status s = ex::ValidateInHandConfig(c); !s.ok()) return FlagError(s, a.object);
  return c;
}

struct MethodRow {
  std::string name;
  absl::StatusOr<inertia::InertiaFit> fit;
  inertia::InertiaErrors errors;
};

std::vector<MethodRow> FitAll(const ex::InHandRun& run) {
  std::vector<MethodRow> rows;
  const std::pair<const char*, inertia::InertiaMethod> methods[] = {
      {"baseline-ls", inertia::InertiaMethod::kBaselineLs},
      {"baseline-ls+sg51", inertia::InertiaMethod::kBaselineLs},
      {"factor-graph", inertia::InertiaMethod::kFactorGraph},
      {"constrained", inertia::InertiaMethod::kConstrained},
      {"density", inertia::InertiaMethod::kDensity}};
  for (const auto& [name, method] : methods) {
    inertia::InertiaOptions o = ex::InHandFitOptions(run, method);
    o.baseline_ls.savitzky_golay = absl::EndsWith(name, "sg51");
    MethodRow r{name, inertia::FitInertia(run.samples, o), {}};
    if (r.fit.ok()) r.errors = inertia::CompareInertia(run.truth, r.fit->params);
    rows.push_back(std::move(r));
  }
  return rows;
}

std::string FitTable(const std::vector<MethodRow>& rows) {
  std::string s = absl::StrFormat("%-17s %9s %11s %8s %9s %8s %11s\n", "method", "eq. 38",
                                  "Riemannian", "mass %", "CoM mm", "mass kg", "consistent");
  for (const MethodRow& r : rows) {
    if (!r.fit.ok()) {
      absl::StrAppend(&s, absl::StrFormat("%-17s failed: %s\n", r.name, r.fit.status().message()));
      continue;
    }
    absl::StrAppend(&s, absl::StrFormat("%-17s %9.4g %11.4g %8.2f %9.2f %8.4f %11s\n", r.name,
                                        r.errors.paper_metric, r.errors.riemannian,
                                        r.errors.mass_percent, r.errors.com_mm, r.fit->params.mass,
                                        r.errors.consistent ? "yes" : "no"));
  }
  return s;
}

std::string StatsTable(const ex::InHandRun& run, const ex::InHandConfig& c) {
  const ex::InHandStats& st = run.stats;
  std::string s = absl::StrFormat(
      "%s, %zu samples at %g Hz, tracker %s%s, force model %s%s; files in the --out directory\n",
      run.object_name, run.samples.samples.size(), c.rate, ex::ToString(c.tracker),
      c.ideal_tracking ? " (ideal)" : "", c.force_model, c.ideal_forces ? " (ideal)" : "");
  absl::StrAppend(
      &s, absl::StrFormat(
              "Newton-Euler residual of the logged true forces: max %.4g N (%.3f %% of m g), "
              "rms %.3g N, torque rms %.3g N m\n",
              st.ne_residual_force_max, 100 * st.ne_residual_force_max / st.mg,
              st.ne_residual_force_rms, st.ne_residual_torque_rms));
  absl::StrAppend(
      &s, absl::StrFormat(
              "net force std: in hand %.4g N, wrist (arm excitation) %.4g N, ratio %.3f\n",
              st.net_force_std, st.wrist_net_force_std,
              st.wrist_net_force_std > 0 ? st.net_force_std / st.wrist_net_force_std : 0.0));
  absl::StrAppend(
      &s, absl::StrFormat("force model: median |f| error %.4g N, angle %.3g deg, |error| <= sigma "
                          "%.1f %%\n",
                          st.median_magnitude_error, st.median_angle_error_deg,
                          100 * st.sigma_coverage));
  absl::StrAppend(
      &s, absl::StrFormat(
              "slip max %.3g mm; tracker error max %.3g mm (final %.3g), rotation max %.3g "
              "deg, r(error, slip) %.2f, dropouts %d; unscheduled contact losses %d; min "
              "normal force %.3g N; wall %.2f s\n",
              st.max_slip_mm, st.tracker_position_error_max_mm, st.tracker_position_error_final_mm,
              st.tracker_rotation_error_max_deg, st.slip_tracker_correlation, st.tracker_dropouts,
              st.contact_losses, st.min_normal_force, st.wall_seconds));
  return s;
}

std::string RunJson(const ex::InHandRun& run, const std::vector<MethodRow>& fits) {
  const ex::InHandStats& st = run.stats;
  std::string s = absl::StrCat(
      "{\"object\":\"", run.object_name, "\",\"samples\":", run.samples.samples.size(),
      ",\"stats\":{\"ne_residual_force_max\":", Num(st.ne_residual_force_max),
      ",\"ne_residual_percent_mg\":", Num(100 * st.ne_residual_force_max / st.mg),
      ",\"ne_residual_torque_rms\":", Num(st.ne_residual_torque_rms),
      ",\"net_force_std\":", Num(st.net_force_std),
      ",\"wrist_net_force_std\":", Num(st.wrist_net_force_std),
      ",\"wrist_same_trajectory_net_force_std\":", Num(st.wrist_same_trajectory_net_force_std),
      ",\"median_magnitude_error\":", Num(st.median_magnitude_error),
      ",\"median_angle_error_deg\":", Num(st.median_angle_error_deg),
      ",\"sigma_coverage\":", Num(st.sigma_coverage), ",\"max_slip_mm\":", Num(st.max_slip_mm),
      ",\"tracker_position_error_max_mm\":", Num(st.tracker_position_error_max_mm),
      ",\"tracker_position_error_final_mm\":", Num(st.tracker_position_error_final_mm),
      ",\"slip_tracker_correlation\":", Num(st.slip_tracker_correlation),
      ",\"tracker_rotation_error_max_deg\":", Num(st.tracker_rotation_error_max_deg),
      ",\"tracker_dropouts\":", st.tracker_dropouts, ",\"contact_losses\":", st.contact_losses,
      ",\"min_normal_force\":", Num(st.min_normal_force),
      ",\"wall_seconds\":", Num(st.wall_seconds), "},\"fits\":[");
  for (size_t i = 0; i < fits.size(); ++i) {
    const MethodRow& r = fits[i];
    absl::StrAppend(&s, i ? "," : "", "{\"method\":\"", r.name,
                    "\",\"ok\":", r.fit.ok() ? "true" : "false");
    if (r.fit.ok())
      absl::StrAppend(&s, ",\"eq38\":", Num(r.errors.paper_metric),
                      ",\"riemannian\":", Num(r.errors.riemannian),
                      ",\"mass_error_percent\":", Num(r.errors.mass_percent),
                      ",\"com_error_mm\":", Num(r.errors.com_mm),
                      ",\"consistent\":", r.errors.consistent ? "true" : "false");
    absl::StrAppend(&s, "}");
  }
  return s + "]}";
}

}  // namespace

void AddInHandSubcommand(CLI::App* experiment, InHandArgs& a) {
  CLI::App* c = experiment->add_subcommand("inhand",
                                           "In-hand inertia data: four fingertips move a box along "
                                           "an exciting trajectory (tactile force model, "
                                           "vision or kinematic tracker)");
  c->add_option("--object", a.object, "box_0..box_4 (the paper's Table II) or FILE.json")
      ->capture_default_str();
  c->add_option("--tracker", a.tracker, "vision|kinematic")->capture_default_str();
  c->add_option("--duration", a.duration, "Logged seconds")->capture_default_str();
  c->add_option("--rate", a.rate, "Log rate (Hz)")->capture_default_str();
  c->add_option("--seed", a.seed, "Seed of the sensor and tracker noise")->capture_default_str();
  c->add_option("--force-model", a.force_model, "Tactile force model: biotac|ideal")
      ->capture_default_str();
  c->add_flag("--ideal-forces", a.ideal_forces, "Log the true forces and contact points");
  c->add_flag("--ideal-tracking", a.ideal_tracking, "Log the true pose");
  c->add_option("--support-fraction", a.support_fraction,
                "Fraction of the weight on an unsensed support (0..0.9)")
      ->capture_default_str();
  c->add_option("--break", a.breaks, "Scheduled contact break CONTACT:START:DURATION (repeatable)");
  c->add_option("--out", a.out_dir, "Directory for the run's files")->capture_default_str();
  c->add_flag("--force", a.force, "Replace an earlier run's files in --out");
  c->add_flag("--fit", a.fit, "Fit every inertia method to the log and print the errors");
  c->add_flag("--no-progress", a.no_progress, "No progress bar on stderr");
  AddOutputFlags(c, &a.output, "{\"object\", \"stats\", \"fits\"}");
  c->footer(
      "Examples:\n  tactforce experiment inhand --object box_2 --tracker kinematic --fit\n"
      "  tactforce experiment inhand --ideal-forces --ideal-tracking --fit --out /tmp/inhand");
  a.cmd = c;
}

int RunInHandCommand(const InHandArgs& a) {
  absl::StatusOr<ex::InHandConfig> c = ConfigFromFlags(a);
  if (!c.ok()) return ReportError(c.status());
  if (absl::Status s = PrepareOutputDir(a.out_dir, a.force, kRunFiles); !s.ok())
    return ReportError(s);
  absl::StatusOr<ex::InHandRun> run;
  {
    ProgressBar bar("inhand", !a.no_progress && ProgressBar::StderrIsTerminal());
    run = ex::RunInHand(*c, [&bar](double f) { bar.Update(f); });
  }
  if (!run.ok()) return ReportError(run.status());
  if (absl::Status s = ex::WriteInHandRun(*run, a.out_dir); !s.ok())
    return ReportError(absl::InvalidArgumentError(absl::StrCat("--out: ", s.message())));
  std::vector<MethodRow> fits;
  if (a.fit) fits = FitAll(*run);
  if (a.output.json()) {
    std::cout << io::IndentJson(RunJson(*run, fits)) << std::flush;
    return kExitOk;
  }
  std::cout << StatsTable(*run, *c);
  if (a.fit) std::cout << FitTable(fits);
  return kExitOk;
}

}  // namespace tactforce::cli
