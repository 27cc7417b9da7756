// `tactforce experiment chain`: flags to a ChainConfig, the run with a
// progress bar on stderr, and the rows as a table or JSON (the field names
// are a contract), with the per-seed estimates beside them.
#include "experiment_chain_command.h"

#include <iostream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "progress.h"
#include "tactforce/experiment/chain.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/io/json.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::cli {
namespace {

namespace ex = tactforce::experiment;
using io::JsonEscape;
using io::JsonNumber;

absl::StatusOr<ex::ChainConfig> Config(const ChainArgs& a) {
  ex::ChainConfig c;
  c.objects.clear();
  for (const std::string& name : a.objects) {
    absl::StatusOr<ex::GraspObject> o = ex::ParseGraspObject(name);
    if (!o.ok()) return io::PrependPath(o.status(), "--objects");
    c.objects.push_back(*o);
  }
  absl::StatusOr<inertia::InertiaMethod> m = inertia::ParseInertiaMethod(a.fit_method);
  if (!m.ok()) return io::PrependPath(m.status(), "--fit-method");
  c.fit_method = *m;
  c.trials = a.trials;
  c.seeds = a.seeds;
  c.seed = a.seed;
  c.probe_trials = a.probe_trials;
  c.inhand_duration = a.inhand_duration;
  c.confidence = a.confidence;
  if (absl::Status s = ex::ValidateChainConfig(c); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("experiment chain: ", s.message()));
  return c;
}

std::string RowJson(const ex::ChainRow& r) {
  const bool ran = r.trials_run > 0;
  return absl::StrCat(
      "{\"object\":", JsonEscape(ex::ToString(r.object)),
      ",\"planning\":", JsonEscape(ex::ToString(r.planning)), ",\"successes\":", r.successes,
      ",\"trials\":", r.trials,
      ",\"median_squeeze_n\":", ran ? JsonNumber(r.median_squeeze_n) : "null",
      ",\"min_slip_margin\":", ran ? JsonNumber(r.min_slip_margin) : "null",
      ",\"median_trial_slip_margin\":", ran ? JsonNumber(r.median_trial_slip_margin) : "null",
      ",\"plan_failures\":", r.plan_failures, ",\"plan_failure\":", JsonEscape(r.plan_failure),
      ",\"estimates_off\":", r.estimates_off ? "true" : "false", "}");
}

std::string V3Json(const Eigen::Vector3d& v) {
  return absl::StrCat("[", JsonNumber(v.x()), ",", JsonNumber(v.y()), ",", JsonNumber(v.z()), "]");
}

std::string EstimateJson(const ex::ChainEstimates& e) {
  return absl::StrCat("{\"object\":", JsonEscape(ex::ToString(e.object)), ",\"seed\":", e.seed,
                      ",\"mu_true\":", JsonNumber(e.mu_true), ",\"mu\":", JsonNumber(e.mu),
                      ",\"mu_sigma\":", JsonNumber(e.mu_sigma),
                      ",\"probes_valid\":", e.probes_valid,
                      ",\"mass_true\":", JsonNumber(e.mass_true), ",\"mass\":", JsonNumber(e.mass),
                      ",\"mass_se\":", JsonNumber(e.mass_se), ",\"com_true\":", V3Json(e.com_true),
                      ",\"com\":", V3Json(e.com), ",\"com_se\":", V3Json(e.com_se),
                      ",\"off_by_more_than_se\":", e.off_by_more_than_se ? "true" : "false", "}");
}

std::string ReportJson(const ex::ChainReport& r) {
  std::string s = "{\"rows\":[";
  for (size_t i = 0; i < r.rows.size(); ++i) absl::StrAppend(&s, i ? "," : "", RowJson(r.rows[i]));
  absl::StrAppend(&s, "],\"estimates\":[");
  for (size_t i = 0; i < r.estimates.size(); ++i)
    absl::StrAppend(&s, i ? "," : "", EstimateJson(r.estimates[i]));
  absl::StrAppend(&s, "],\"wall_seconds\":", JsonNumber(r.wall_seconds), "}");
  return s;
}

std::string ReportTable(const ChainArgs& a, const ex::ChainReport& r) {
  std::string out = absl::StrFormat(
      "Probe -> fit -> plan -> lift (estimated-force feedback), %d seeds from %d, %d trials each\n",
      a.seeds, a.seed, a.trials);
  absl::StrAppend(&out, absl::StrFormat("%-9s %-10s %10s %8s %16s %16s %14s %6s\n", "object",
                                        "planning", "success", "rate", "median squeeze N",
                                        "min slip margin", "median of min", "off"));
  for (const ex::ChainRow& w : r.rows) {
    const bool ran = w.trials_run > 0;
    absl::StrAppend(
        &out, absl::StrFormat(
                  "%-9s %-10s %6d/%-3d %7.0f%% %16s %16s %14s %6s%s\n", ex::ToString(w.object),
                  ex::ToString(w.planning), w.successes, w.trials, 100.0 * w.successes / w.trials,
                  ran ? absl::StrFormat("%.3f", w.median_squeeze_n) : "-",
                  ran ? absl::StrFormat("%.3f", w.min_slip_margin) : "-",
                  ran ? absl::StrFormat("%.3f", w.median_trial_slip_margin) : "-",
                  w.estimates_off ? "yes" : "no",
                  w.plan_failures
                      ? absl::StrCat("  (", w.plan_failures, " plans failed: ", w.plan_failure, ")")
                      : ""));
  }
  absl::StrAppend(&out, "Estimates (probe mean +- spread; in-hand fit +- standard error):\n");
  for (const ex::ChainEstimates& e : r.estimates)
    absl::StrAppend(&out, absl::StrFormat("  %-9s seed %d: mu %.4f +- %.4f (true %.3f, %d probes); "
                                          "mass %.4f +- %.4f kg (true %.4f); "
                                          "CoM error %.1f mm (se %.1f mm)%s\n",
                                          ex::ToString(e.object), e.seed, e.mu, e.mu_sigma,
                                          e.mu_true, e.probes_valid, e.mass, e.mass_se, e.mass_true,
                                          1e3 * (e.com - e.com_true).norm(), 1e3 * e.com_se.norm(),
                                          e.off_by_more_than_se ? "  [off > se]" : ""));
  absl::StrAppend(&out, absl::StrFormat("%.1f s wall\n", r.wall_seconds));
  return out;
}

}  // namespace

CLI::App* AddChainCommand(CLI::App* experiment, ChainArgs& args) {
  CLI::App* p = experiment->add_subcommand("chain",
                                           "Probe friction, fit inertia in hand, plan the lift "
                                           "with truth / point estimates / estimates with "
                                           "uncertainty, run each closed loop");
  p->add_option("--objects", args.objects, "Grasp objects: sphere, wrench, cylinder, cube")
      ->delimiter(',')
      ->check(CLI::IsMember({"sphere", "wrench", "cylinder", "cube"}))
      ->capture_default_str();
  p->add_option("--trials", args.trials, "Closed-loop trials per object, seed and planning")
      ->check(Between(1, 10000))
      ->capture_default_str();
  p->add_option("--seeds", args.seeds,
                "Seeds per object (each: its own probe, in-hand run and fit)")
      ->check(Between(1, 1000))
      ->capture_default_str();
  p->add_option("--seed", args.seed, "First seed")->capture_default_str();
  p->add_option("--probe-trials", args.probe_trials,
                "In-grasp friction probes per object and seed (>= 2: a spread)")
      ->check(Between(2, 1000))
      ->capture_default_str();
  p->add_option("--inhand-duration", args.inhand_duration,
                "Seconds of in-hand excitation per object and seed")
      ->check(Between(1, 120))
      ->capture_default_str();
  p->add_option("--confidence", args.confidence,
                "kappa_b: standard deviations of the parameter ellipsoid")
      ->check(Between(0, 10))
      ->capture_default_str();
  p->add_option("--fit-method", args.fit_method,
                "In-hand fit: baseline-ls, factor-graph, constrained, density")
      ->check(CLI::IsMember({"baseline-ls", "factor-graph", "constrained", "density"}))
      ->capture_default_str();
  AddOutputFlags(
      p, &args.output,
      "{\"rows\":[{\"object\",\"planning\",\"successes\",\"trials\",\"median_squeeze_n\","
      "\"min_slip_margin\"}...],\"estimates\":[...]}");
  p->add_flag("--no-progress", args.no_progress, "No progress bar on stderr");
  p->footer(
      "Examples:\n"
      "  tactforce experiment chain --objects wrench --trials 5 --seeds 2\n"
      "  tactforce experiment chain --json");
  args.app = p;
  return p;
}

int RunChainCommand(const ChainArgs& a) {
  absl::StatusOr<ex::ChainConfig> c = Config(a);
  if (!c.ok()) return ReportError(c.status());
  ProgressBar bar("chain", !a.no_progress);
  absl::StatusOr<ex::ChainReport> r = ex::RunChain(*c, [&](int done, int total) {
    bar.Update(static_cast<double>(done) / total, absl::StrCat(done, "/", total, " steps"));
  });
  bar.Finish();
  if (!r.ok()) return ReportError(r.status());
  if (a.output.json())
    std::cout << io::IndentJson(ReportJson(*r)) << std::flush;
  else
    std::cout << ReportTable(a, *r);
  return kExitOk;
}

}  // namespace tactforce::cli
