// `tactforce experiment ablation`: flags to an AblationConfig, the run with a
// progress bar, the markdown table or the JSON on stdout.
#include "experiment_ablation_command.h"

#include <algorithm>
#include <iostream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "progress.h"
#include "tactforce/io/json.h"
#include "tactforce/experiment/ablation.h"

namespace tactforce::cli {
namespace {

namespace ex = tactforce::experiment;

absl::StatusOr<ex::AblationConfig> ConfigFromFlags(const AblationArgs& a) {
  ex::AblationConfig c;
  c.seeds = a.seeds;
  c.first_seed = a.first_seed;
  c.duration = a.duration;
  c.rate = a.rate;
  c.sources = a.sources;
  for (const std::string& name : a.methods) {
    bool found = false;
    std::vector<std::string> names;
    for (ex::AblationMethod m : ex::AllAblationMethods()) {
      names.push_back(ex::ToString(m));
      if (name == ex::ToString(m)) c.methods.push_back(m), found = true;
    }
    if (!found)
      return absl::InvalidArgumentError(absl::StrCat("--methods: unknown '", name, "' (expected ",
                                                     absl::StrJoin(names, ", "), ")"));
  }
  if (absl::Status s = ex::ValidateAblationConfig(c); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat("--", s.message()));
  // Unknown source names are refused before any run.
  std::vector<std::string> known;
  for (const ex::AblationSource& s : ex::BuiltInAblationSources(c)) known.push_back(s.name);
  for (const std::string& name : c.sources)
    if (std::find(known.begin(), known.end(), name) == known.end())
      return absl::InvalidArgumentError(absl::StrCat("--sources: unknown '", name, "' (expected ",
                                                     absl::StrJoin(known, ", "), ")"));
  return c;
}

}  // namespace

void AddAblationSubcommand(CLI::App* experiment, AblationArgs& a) {
  CLI::App* cmd = experiment->add_subcommand(
      "ablation",
      "The paper's inertia ablation: every method on every source, medians beside Tables I-IV");
  cmd->add_option("--seeds", a.seeds, "Runs per method and source (seeds --first-seed..)")
      ->check(Between(1, 10000))
      ->capture_default_str();
  cmd->add_option("--first-seed", a.first_seed, "First seed")->capture_default_str();
  cmd->add_option("--duration", a.duration, "Seconds of every trajectory")
      ->check(GreaterThan(0))
      ->capture_default_str();
  cmd->add_option("--rate", a.rate, "Sample rate (Hz)")
      ->check(GreaterThan(0))
      ->capture_default_str();
  cmd->add_option(
         "--sources", a.sources,
         "Sources (default all): sim-0,sim-0.1,sim-0.25,sim-0.5,sim-1,wrist-moderate,inhand-vision,"
         "inhand-kinematic")
      ->delimiter(',');
  cmd->add_option("--methods", a.methods,
                  "Methods (default all): "
                  "baseline-ls,baseline-ls+sg51,baseline-fg,fg-no-c,fg-c,fg-c-g,constrained,"
                  "density")
      ->delimiter(',');
  cmd->add_flag("--no-progress", a.no_progress, "No progress bar on stderr");
  AddOutputFlags(cmd, &a.output, "{\"rows\": [{method, source, median_eq38, ...}]}");
  cmd->footer(
      "Examples:\n"
      "  tactforce experiment ablation --seeds 5\n"
      "  tactforce experiment ablation --seeds 2 --sources sim-0.1,wrist-moderate --duration 3 "
      "--json");
  a.cmd = cmd;
}

int RunAblationCommand(const AblationArgs& a) {
  absl::StatusOr<ex::AblationConfig> config = ConfigFromFlags(a);
  if (!config.ok()) return ReportError(config.status());
  ProgressBar bar("ablation", !a.no_progress);
  config->progress = [&bar](double f) { bar.Update(f); };
  absl::StatusOr<ex::AblationTable> table = ex::RunAblation(*config);
  bar.Finish();
  if (!table.ok()) return ReportError(table.status());
  std::cout << (a.output.json() ? io::IndentJson(ex::AblationJson(*table))
                                : ex::AblationMarkdown(*table));
  return 0;
}

}  // namespace tactforce::cli
