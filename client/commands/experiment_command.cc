// `tactforce experiment grasp` (grasp-and-lift batches per object and
// feedback mode: a table or JSON, SVG traces, per-trial details) and
// `tactforce experiment slope` (slope-method friction vs the probing
// estimate, and MuJoCo's creep): flags to configurations, runs, output.
#include "experiment_command.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/strip.h"
#include "cli_common.h"
#include "experiment_grasp_report.h"
#include "progress.h"
#include "tactforce/experiment/grasp.h"
#include "tactforce/experiment/slope.h"
#include "tactforce/sim/sensor_model.h"
#include "tactforce/sim/taxel_array.h"
#include "tactforce/io/json.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

namespace ex = tactforce::experiment;

std::string JsonNumber(double v) {
  if (!std::isfinite(v)) return "null";
  return absl::StrFormat("%.6g", v);
}

// What `experiment grasp` runs: objects x feedback modes, each a batch of
// --trials trials with `base` as the shared configuration.
struct GraspRun {
  std::vector<ex::GraspObject> objects;
  std::vector<ex::Feedback> modes;
  ex::GraspConfig base;
};

// --object and --feedback ("all" and "both" expand).
absl::Status SetObjectsAndModes(const ExperimentArgs& a, GraspRun* run) {
  if (a.object == "all") {
    run->objects = ex::AllGraspObjects();
  } else {
    auto o = ex::ParseGraspObject(a.object);
    if (!o.ok()) return absl::InvalidArgumentError(absl::StrCat("--", o.status().message()));
    run->objects = {*o};
  }
  if (a.feedback == "both") {
    run->modes = {ex::Feedback::kRaw, ex::Feedback::kEstimated};
  } else {
    auto f = ex::ParseFeedback(a.feedback);
    if (!f.ok()) return absl::InvalidArgumentError(absl::StrCat("--", f.status().message()));
    run->modes = {*f};
  }
  return absl::OkStatus();
}

// --seed, --estimator, --admittance, --ideal-sensors / --sensor-model and
// --plots (the directory is created; trial 0 of each batch is traced).
absl::Status SetBaseConfig(const ExperimentArgs& a, ex::GraspConfig* base) {
  base->seed = a.seed;
  if (a.estimator == "projection")
    base->estimator = estimator::EstimateMethod::kProjection;
  else if (a.estimator == "normal-lsq")
    base->estimator = estimator::EstimateMethod::kNormalLsq;
  else
    return absl::InvalidArgumentError(absl::StrCat("--estimator: unknown '", a.estimator,
                                                   "' (expected projection or normal-lsq)"));
  auto adm = ex::ParseAdmittance(a.admittance);
  if (!adm.ok()) return absl::InvalidArgumentError(absl::StrCat("--", adm.status().message()));
  base->admittance = *adm;
  if (a.ideal && !a.sensor_model_path.empty())
    return absl::InvalidArgumentError("--ideal-sensors: cannot be combined with --sensor-model");
  if (a.ideal) base->sensors = ex::SensorMode::kIdeal;
  if (!a.sensor_model_path.empty()) {
    auto m = sim::LoadSensorModel(a.sensor_model_path);
    if (!m.ok())
      return absl::InvalidArgumentError(absl::StrCat("--sensor-model: ", m.status().message()));
    base->sensors = ex::SensorMode::kModel;
    base->sensor_model = *m;
  }
  if (!a.plots_dir.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(a.plots_dir, ec);
    if (ec)
      return absl::InvalidArgumentError(
          absl::StrCat("--plots: cannot create ", a.plots_dir, ": ", ec.message()));
    base->trace_trials = 1;
  }
  return absl::OkStatus();
}

// --sensors (taxel: one sim::TaxelArray per fingertip, --taxel-ranges) and --protocol.
absl::Status SetSensorsAndProtocol(const ExperimentArgs& a, ex::GraspConfig* base) {
  auto array = ex::ParseSensorArray(a.sensors);
  if (!array.ok()) return absl::InvalidArgumentError(absl::StrCat("--", array.status().message()));
  base->sensor_array = *array;
  if (*array == ex::SensorArray::kTaxel && (a.ideal || !a.sensor_model_path.empty()))
    return absl::InvalidArgumentError(absl::StrCat(a.ideal ? "--ideal-sensors" : "--sensor-model",
                                                   ": applies to --sensors channel only"));
  if (!a.taxel_ranges_path.empty()) {
    if (*array != ex::SensorArray::kTaxel)
      return absl::InvalidArgumentError("--taxel-ranges: needs --sensors taxel");
    auto r = sim::LoadTaxelRanges(a.taxel_ranges_path);
    if (!r.ok())
      return absl::InvalidArgumentError(absl::StrCat("--taxel-ranges: ", r.status().message()));
    base->taxel_ranges = *r;
  }
  if (a.contact_cap_deg.has_value() && *array != ex::SensorArray::kTaxel)
    return absl::InvalidArgumentError("--contact-cap: needs --sensors taxel");
  if (a.contact_cap_deg.has_value()) base->contact_cap_deg = *a.contact_cap_deg;
  auto sensing = ex::ParseContactSensing(a.contact_sensing);
  if (!sensing.ok())
    return absl::InvalidArgumentError(absl::StrCat(
        "--contact-sensing", absl::StripPrefix(sensing.status().message(), "contact_sensing")));
  if (*sensing != ex::ContactSensing::kTaxelMean && *array != ex::SensorArray::kTaxel)
    return absl::InvalidArgumentError("--contact-sensing: needs --sensors taxel");
  base->contact_sensing = *sensing;
  base->normal_uncertainty_deg = a.normal_uncertainty_deg;
  auto protocol = ex::ParseProtocol(a.protocol);
  if (!protocol.ok())
    return absl::InvalidArgumentError(absl::StrCat("--", protocol.status().message()));
  base->phases = ex::ProtocolPhases(*protocol);
  return absl::OkStatus();
}

absl::StatusOr<GraspRun> GraspRunFromFlags(const ExperimentArgs& a) {
  GraspRun run;
  TF_RETURN_IF_ERROR(SetObjectsAndModes(a, &run));
  if (a.trials < 1)
    return absl::InvalidArgumentError(absl::StrFormat("--trials: must be >= 1, got %d", a.trials));
  // Sensors first: a flag that does not apply to --sensors taxel is named before its file is read.
  TF_RETURN_IF_ERROR(SetSensorsAndProtocol(a, &run.base));
  TF_RETURN_IF_ERROR(SetBaseConfig(a, &run.base));
  return run;
}

// Trial 0's force traces of the batch run with `c` as PLOTS/OBJECT_FEEDBACK.svg.
absl::Status WriteTracePlot(const std::string& plots_dir, const ex::GraspConfig& c,
                            const ex::TrialResult& t0) {
  TF_ASSIGN_OR_RETURN(auto setup, ex::GraspSetup::Create(c));
  const std::string title = absl::StrFormat(
      "%s, %s feedback, trial 0 (%s): desired / estimated / raw / true normal force",
      ex::ToString(c.object), ex::ToString(c.feedback), t0.success ? "success" : t0.failure);
  const std::string path =
      (std::filesystem::path(plots_dir) /
       absl::StrCat(ex::ToString(c.object), "_", ex::ToString(c.feedback), ".svg"))
          .string();
  if (absl::Status st =
          io::WriteTextFile(path, io::RenderSvg(ex::TracePlot(t0, setup->finger_names(), title)));
      !st.ok())
    return io::PrependPath(st, "--plots");
  return absl::OkStatus();
}

// --details: one line per trial on stderr.
void PrintTrialDetails(const ex::GraspConfig& c, const ex::BatchSummary& b) {
  for (const ex::TrialResult& t : b.results) {
    std::string sensed;
    if (c.sensor_array == ex::SensorArray::kTaxel)
      sensed = absl::StrFormat(
          "  slip margin %.2f  sensed contact off by %.2f mm, %.1f deg; polar %s deg",
          t.min_slip_margin, t.contact_location_error * 1e3, t.contact_normal_error_deg,
          absl::StrJoin(t.contact_polar_deg, "/",
                        [](std::string* o, double v) { absl::StrAppendFormat(o, "%.0f", v); }));
    std::cerr << absl::StrFormat(
        "%s %s trial %d: %s%s  slip %.2f mm  rotation %.2f deg  force error %.3f N%s\n",
        ex::ToString(c.object), ex::ToString(c.feedback), t.trial,
        t.success ? "success" : t.failure,
        t.success ? "" : absl::StrCat(" (", ex::ToString(t.cause), ")"), t.max_slip * 1e3,
        t.max_rotation_deg, t.force_error, sensed);
  }
}

// Every object x mode batch in order, with `bar` counting trials; the
// summaries without their per-trial results.
absl::StatusOr<std::vector<ex::BatchSummary>> RunGraspBatches(const ExperimentArgs& a,
                                                              const GraspRun& run,
                                                              ProgressBar& bar) {
  const int total_trials = static_cast<int>(run.objects.size() * run.modes.size()) * a.trials;
  int done_before = 0;
  std::vector<ex::BatchSummary> rows;
  for (ex::GraspObject o : run.objects) {
    for (ex::Feedback f : run.modes) {
      ex::GraspConfig c = run.base;
      c.object = o;
      c.feedback = f;
      const std::string label = absl::StrCat(ex::ToString(o), " ", ex::ToString(f));
      auto b = ex::RunGraspBatch(c, a.trials, [&](int done) {
        bar.Update(static_cast<double>(done_before + done) / std::max(1, total_trials),
                   absl::StrCat(done_before + done, "/", total_trials, " ", label));
      });
      if (!b.ok()) {
        bar.Finish();
        return b.status();
      }
      done_before += a.trials;
      if (!a.plots_dir.empty() && !b->results.empty()) {
        TF_RETURN_IF_ERROR(WriteTracePlot(a.plots_dir, c, b->results[0]));
      }
      if (a.details && !a.output.json()) PrintTrialDetails(c, *b);
      b->results.clear();
      rows.push_back(std::move(*b));
    }
  }
  return rows;
}

// {"results":[{object, feedback, trials, successes, ...}], "seed", ...}
std::string GraspJson(const ExperimentArgs& a, const std::vector<ex::BatchSummary>& rows,
                      double wall) {
  std::string s = "{\"results\":[";
  for (size_t i = 0; i < rows.size(); ++i) {
    const ex::BatchSummary& r = rows[i];
    absl::StrAppend(
        &s, i ? "," : "", "{\"object\":\"", ex::ToString(r.object), "\",\"feedback\":\"",
        ex::ToString(r.feedback), "\",\"trials\":", r.trials, ",\"successes\":", r.successes,
        ",\"force_error_mean\":", JsonNumber(r.force_error_mean),
        ",\"force_error_std\":", JsonNumber(r.force_error_std), ",\"drops\":", r.drops,
        ",\"feedback_error_mean\":", JsonNumber(r.feedback_error_mean),
        ",\"converged\":", r.converged,
        ",\"converge_time_mean\":", r.converged ? JsonNumber(r.converge_time_mean) : "null",
        ",\"sim_seconds\":", JsonNumber(r.sim_seconds),
        ",\"wall_seconds\":", JsonNumber(r.wall_seconds), GraspSplitJsonMembers(r), "}");
  }
  absl::StrAppend(&s, "],\"seed\":", a.seed, ",\"estimator\":\"", a.estimator,
                  "\",\"admittance\":\"", a.admittance, "\",\"sensors\":\"", a.sensors,
                  "\",\"protocol\":\"", a.protocol, "\",\"wall_seconds\":", JsonNumber(wall), "}");
  return s;
}

// One row per batch and a line with the wall time and the settings.
std::string GraspTable(const ExperimentArgs& a, const std::vector<ex::BatchSummary>& rows,
                       double wall) {
  std::string out = absl::StrFormat("%-9s %-10s %9s %6s %22s %14s %14s %10s\n", "object",
                                    "feedback", "success", "drops", "force error (N) mean/std",
                                    "feedback err", "converge (s)", "x realtime");
  for (const ex::BatchSummary& r : rows) {
    absl::StrAppend(
        &out, absl::StrFormat(
                  "%-9s %-10s %4d/%-4d %6d %13.3f / %-6.3f %14.3f %14s %10.1f\n",
                  ex::ToString(r.object), ex::ToString(r.feedback), r.successes, r.trials, r.drops,
                  r.force_error_mean, r.force_error_std, r.feedback_error_mean,
                  r.converged ? absl::StrFormat("%.3f (%d)", r.converge_time_mean, r.converged)
                              : std::string("never"),
                  r.wall_seconds > 0 ? r.sim_seconds / r.wall_seconds : 0.0));
  }
  absl::StrAppend(
      &out,
      absl::StrFormat("total %.1f s wall; seed %d; estimator %s; admittance %s; sensors %s\n", wall,
                      a.seed, a.estimator, a.admittance,
                      a.sensors == "taxel" ? "42-taxel arrays, GeoDEx ranges per taxel and trial"
                      : a.ideal            ? "ideal"
                      : a.sensor_model_path.empty() ? "GeoDEx error ranges per trial"
                                                    : a.sensor_model_path));
  absl::StrAppend(&out, GraspSplitTable(rows, a.protocol == "paper"));
  return out;
}

int RunGrasp(const ExperimentArgs& a) {
  absl::StatusOr<GraspRun> run = GraspRunFromFlags(a);
  if (!run.ok()) return ReportError(run.status());
  ProgressBar bar("trials", !a.no_progress && ProgressBar::StderrIsTerminal(),
                  std::chrono::milliseconds(0));
  const auto wall0 = std::chrono::steady_clock::now();
  absl::StatusOr<std::vector<ex::BatchSummary>> rows = RunGraspBatches(a, *run, bar);
  if (!rows.ok()) return ReportError(rows.status());
  bar.Finish();
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  if (a.output.json()) {
    std::cout << io::IndentJson(GraspJson(a, *rows, wall)) << std::flush;
  } else {
    std::cout << GraspTable(a, *rows, wall);
  }
  return kExitOk;
}

// MuJoCo's creep under static friction at one load ratio of the cone.
struct Creep {
  std::string settings;  // "chosen" or "mujoco-default"
  double ratio, velocity;
};

// --creep: creep at 50 % and 90 % of the cone with both solver settings.
absl::StatusOr<std::vector<Creep>> MeasureCreepTable() {
  std::vector<Creep> creep;
  for (const auto& [name, p] :
       {std::pair{std::string("chosen"), ex::PhysicsSettings{}},
        std::pair{std::string("mujoco-default"), ex::PhysicsSettings::MujocoDefaults()}}) {
    for (double ratio : {0.5, 0.9}) {
      TF_ASSIGN_OR_RETURN(auto v, ex::MeasureCreep(p, 0.5, ratio));
      creep.push_back({name, ratio, v});
    }
  }
  return creep;
}

std::string SlopeRowJson(const ex::SlopeRow& r) {
  return absl::StrCat(
      "{\"mu\":", JsonNumber(r.mu), ",\"slip_tilt_deg\":", JsonNumber(r.slip_tilt_deg),
      ",\"mu_slope\":", JsonNumber(r.mu_slope),
      ",\"mu_probe\":", r.probe_valid ? JsonNumber(r.mu_probe) : "null",
      ",\"difference\":", r.probe_valid ? JsonNumber(r.mu_probe - r.mu_slope) : "null", "}");
}

// {"results":[...],"mujoco_default_results":[...],"creep":[...]}
std::string SlopeJson(const std::vector<ex::SlopeRow>& rows,
                      const std::vector<ex::SlopeRow>& default_rows,
                      const std::vector<Creep>& creep) {
  std::string s = "{\"results\":[";
  for (size_t i = 0; i < rows.size(); ++i) absl::StrAppend(&s, i ? "," : "", SlopeRowJson(rows[i]));
  absl::StrAppend(&s, "],\"mujoco_default_results\":[");
  for (size_t i = 0; i < default_rows.size(); ++i)
    absl::StrAppend(&s, i ? "," : "", SlopeRowJson(default_rows[i]));
  absl::StrAppend(&s, "],\"creep\":[");
  for (size_t i = 0; i < creep.size(); ++i)
    absl::StrAppend(&s, i ? "," : "", "{\"settings\":\"", creep[i].settings,
                    "\",\"mu\":0.5,\"load_ratio\":", JsonNumber(creep[i].ratio),
                    ",\"velocity_m_per_s\":", JsonNumber(creep[i].velocity), "}");
  absl::StrAppend(&s, "]}");
  return s;
}

// Slope vs probe per friction coefficient.
std::string SlopeTable(const std::vector<ex::SlopeRow>& rows) {
  std::string out = absl::StrFormat("%6s %11s %9s %9s %9s %9s %14s\n", "mu", "slip tilt",
                                    "mu_slope", "slope-mu", "mu_probe", "probe-mu", "probe-slope");
  for (const ex::SlopeRow& r : rows) {
    if (r.probe_valid)
      absl::StrAppend(&out,
                      absl::StrFormat("%6.3f %9.2f° %9.4f %+9.4f %9.4f %+9.4f %+14.4f\n", r.mu,
                                      r.slip_tilt_deg, r.mu_slope, r.mu_slope - r.mu, r.mu_probe,
                                      r.mu_probe - r.mu, r.mu_probe - r.mu_slope));
    else
      absl::StrAppend(&out,
                      absl::StrFormat("%6.3f %9.2f° %9.4f %+9.4f %9s (%s)\n", r.mu, r.slip_tilt_deg,
                                      r.mu_slope, r.mu_slope - r.mu, "no slip", r.probe_message));
  }
  return out;
}

// --mu and --tilt-rate checked by the library; its message names the flag.
absl::Status CheckSlopeFlags(const ex::SlopeConfig& c) {
  absl::Status s = ex::ValidateSlopeConfig(c);
  if (s.ok()) return s;
  const std::string m(s.message());
  const char* flag = absl::StartsWith(m, "mus")         ? "--mu"
                     : absl::StartsWith(m, "tilt_rate") ? "--tilt-rate"
                                                        : "experiment slope";
  return absl::InvalidArgumentError(absl::StrCat(flag, ": ", m));
}

int RunSlope(const ExperimentArgs& a) {
  ex::SlopeConfig c;
  c.mus = a.mus;
  c.tilt_rate_deg = a.tilt_rate;
  if (absl::Status s = CheckSlopeFlags(c); !s.ok()) return ReportError(s);
  auto rows = ex::RunSlopeTable(c);
  if (!rows.ok()) return ReportError(rows.status());
  std::vector<Creep> creep;
  std::vector<ex::SlopeRow> default_rows;
  if (a.creep) {
    absl::StatusOr<std::vector<Creep>> measured = MeasureCreepTable();
    if (!measured.ok()) return ReportError(measured.status());
    creep = *std::move(measured);
    ex::SlopeConfig d = c;
    d.physics = ex::PhysicsSettings::MujocoDefaults();
    auto r = ex::RunSlopeTable(d);
    if (!r.ok()) return ReportError(r.status());
    default_rows = *r;
  }
  if (a.output.json()) {
    std::cout << io::IndentJson(SlopeJson(*rows, default_rows, creep)) << std::flush;
    return kExitOk;
  }
  std::cout << "Slope method vs probing (chosen solver settings):\n" << SlopeTable(*rows);
  if (a.creep) {
    std::cout << "\nSame with MuJoCo's default solver settings:\n" << SlopeTable(default_rows);
    std::cout << "\nCreep under static friction (mu 0.5, fingertip 0.05 kg on a tilted plate):\n";
    for (const Creep& k : creep)
      std::cout << absl::StrFormat("  %-15s load %.0f %% of the cone: %.3g mm/s\n", k.settings,
                                   100 * k.ratio, 1e3 * k.velocity);
  }
  return kExitOk;
}

CLI::App* AddGraspSubcommand(CLI::App* cmd, ExperimentArgs& args) {
  CLI::App* g = cmd->add_subcommand("grasp",
                                    "Grasp-and-lift trials with force feedback on raw or estimated "
                                    "tactile forces (GeoDEx Table III)");
  g->add_option("--object", args.object, "sphere|wrench|cylinder|cube|all")
      ->check(CLI::IsMember({"sphere", "wrench", "cylinder", "cube", "all"}))
      ->capture_default_str();
  g->add_option("--trials", args.trials, "Seeded trials per object and feedback mode")
      ->check(Between(1, 10000))
      ->capture_default_str();
  g->add_option("--feedback", args.feedback, "estimated|raw|both")
      ->check(CLI::IsMember({"estimated", "raw", "both"}))
      ->capture_default_str();
  g->add_option("--seed", args.seed, "Seed of the per-trial sensor-error draws")
      ->capture_default_str();
  AddOutputFlags(g, &args.output, "{\"results\":[...]}");
  g->add_option("--plots", args.plots_dir,
                "Write an SVG force-trace plot of trial 0 per object and mode here")
      ->type_name("DIR");
  g->add_option("--estimator", args.estimator,
                "Estimate for estimated feedback: normal-lsq (ours) | projection (GeoDEx)")
      ->check(CLI::IsMember({"normal-lsq", "projection"}))
      ->capture_default_str();
  g->add_option("--admittance", args.admittance,
                "full: target += K^-1 (f_desired - f_observed), 3D (the paper's loop); normal: "
                "along the sensed normal only, planned tangential force fed forward")
      ->capture_default_str();
  g->add_option(
       "--sensor-model", args.sensor_model_path,
       "Sensor model JSON for every fingertip (default: GeoDEx error ranges drawn per trial)")
      ->type_name("FILE");
  g->add_flag("--ideal-sensors", args.ideal, "Readings are the true normal forces");
  g->add_option(
       "--sensors", args.sensors,
       "channel: one sensor-model channel per fingertip; taxel: a 42-taxel array per fingertip fed "
       "MuJoCo's contact point and force, contacts sensed from the taxels")
      ->capture_default_str();
  g->add_option(
       "--taxel-ranges", args.taxel_ranges_path,
       "Taxel ranges JSON (tactforce.taxel_ranges.v1) for --sensors taxel (default: the paper's)")
      ->type_name("FILE");
  g->add_option("--contact-cap", args.contact_cap_deg,
                "--sensors taxel: each contact lands on its fingertip at a polar angle from the "
                "apex drawn uniformly by area over this cap (deg, 0-90; 0 = on the apex taxel; "
                "default 60, the dome's outermost taxel ring)")
      ->check(CLI::Range(0.0, 90.0));
  g->add_option(
       "--contact-sensing", args.contact_sensing,
       "--sensors taxel: the contact planned on, from the taxels: mean (GeoDEx: force-"
       "weighted mean position and normal) or surface (that position projected onto the "
       "fingertip's surface, its normal there); what-if: true-normal, true-location, truth")
      ->capture_default_str();
  g->add_option("--normal-uncertainty", args.normal_uncertainty_deg,
                "Admittance full: the contact normals' angular uncertainty (deg); the tangential "
                "force error within |f| sin of it is not acted on (negative: the taxel layout's "
                "resolution with --sensors taxel, 0 with channel)")
      ->check(CLI::Range(-1.0, 89.0))
      ->capture_default_str();
  g->add_option("--protocol", args.protocol,
                "short: close, settle, hold, lift 5 cm, hold 1 s, place; paper: GeoDEx Fig. 12's "
                "50 s (lift at 27 s, placed at 33 s, feedback switched at 40 s)")
      ->capture_default_str();
  g->add_flag("--no-progress", args.no_progress, "No progress bar on stderr");
  g->add_flag("--details", args.details,
              "Also print one line per trial (outcome, slip, rotation) on stderr");
  g->footer(
      "Prints success rates per object and feedback mode. Examples:\n"
      "  tactforce experiment grasp --object wrench --trials 5\n"
      "  tactforce experiment grasp --object all --trials 20 --plots /tmp/plots --json\n"
      "  tactforce experiment grasp --object all --sensors taxel --trials 50 --feedback both");
  return g;
}

CLI::App* AddSlopeSubcommand(CLI::App* cmd, ExperimentArgs& args) {
  CLI::App* s = cmd->add_subcommand("slope",
                                    "Friction by the slope method vs the probing estimate, and "
                                    "MuJoCo's creep under static friction");
  s->add_option("--mu", args.mus, "MJCF friction coefficients")
      ->delimiter(',')
      ->capture_default_str();
  s->add_option("--tilt-rate", args.tilt_rate, "Plate tilt rate (deg/s)")
      ->check(Between(0.01, 90))
      ->capture_default_str();
  s->add_flag("--creep,!--no-creep", args.creep,
              "Also measure creep and repeat with MuJoCo's default settings");
  AddOutputFlags(s, &args.output, "the slope results");
  s->footer(
      "Examples:\n"
      "  tactforce experiment slope --mu 0.3,0.5 --no-creep\n"
      "  tactforce experiment slope --json");
  return s;
}

}  // namespace

CLI::App* AddExperimentCommand(CLI::App& app, ExperimentArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "experiment",
      "Closed-loop experiments in MuJoCo (grasp, slope, probe, inhand, ablation, chain)");
  cmd->require_subcommand(1);
  args.grasp = AddGraspSubcommand(cmd, args);
  args.slope = AddSlopeSubcommand(cmd, args);
  AddInHandSubcommand(cmd, args.inhand);
  AddAblationSubcommand(cmd, args.ablation);
  AddProbeCommand(cmd, args.probe);
  AddChainCommand(cmd, args.chain);
  return cmd;
}

int RunExperiment(const ExperimentArgs& args) {
  if (args.grasp && args.grasp->parsed()) return RunGrasp(args);
  if (args.slope && args.slope->parsed()) return RunSlope(args);
  if (args.inhand.cmd && args.inhand.cmd->parsed()) return RunInHandCommand(args.inhand);
  if (args.ablation.cmd && args.ablation.cmd->parsed()) return RunAblationCommand(args.ablation);
  if (args.probe.app && args.probe.app->parsed()) return RunProbe(args.probe);
  if (args.chain.app && args.chain.app->parsed()) return RunChainCommand(args.chain);
  return ReportError(absl::InvalidArgumentError(
      "experiment: give grasp, slope, probe, inhand, ablation or chain"));
}

}  // namespace tactforce::cli
