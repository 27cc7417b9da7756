// `tactforce audit` (measured data from one CSV or two aligned streams,
// the audit, its report directory and summary) and `tactforce simulate
// sensor` (a simulated fingertip run against a reference force).
#include "audit_command.h"

#include <iostream>

#include "absl/strings/str_cat.h"
#include "cli_common.h"
#include "tactforce/audit/audit.h"
#include "tactforce/audit/measured_data.h"
#include "tactforce/sim/sensor_model.h"
#include "tactforce/sim/simulate.h"

namespace tactforce::cli {

CLI::App* AddAuditCommand(CLI::App& app, AuditArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "audit", "Show what the sensor model gets wrong on measured data, name the cause, extend it");
  auto* csv = cmd->add_option("--csv", args.csv,
                              "Measured data: t,reference,reading[,shear][,trial], or per taxel "
                              "t,reference,taxel_0,...,taxel_<N-1>[,reading][,shear][,trial]; - = stdin")
                  ->type_name("FILE");
  auto* ref = cmd->add_option("--reference", args.reference_path, "Reference stream: t,value[,shear]; - = stdin")
                  ->type_name("FILE");
  auto* reading = cmd->add_option("--reading", args.reading_path, "Reading stream: t,value; - = stdin")
                      ->type_name("FILE");
  csv->excludes(ref)->excludes(reading);
  ref->needs(reading);
  reading->needs(ref);
  auto* fixed = cmd->add_option("--clock-offset", args.clock_offset,
                                "Two streams: fix the clock offset (reading clock minus reference clock, s) instead "
                                "of estimating it; the sensor's delay is then audited")
                    ->each([&args](const std::string&) { args.clock_offset_given = true; });
  auto* none = cmd->add_flag("--no-clock-offset", args.no_clock_offset,
                             "Two streams: no clock-offset estimation (offset 0; a clock offset then shows as 'delay')");
  auto* search = cmd->add_option("--max-clock-offset", args.max_clock_offset,
                                 "Two streams: estimate the clock offset within +/- this (s; default estimation)")
                     ->check(GreaterThan(0))
                     ->capture_default_str();
  auto* centre = cmd->add_option("--clock-offset-centre", args.clock_offset_centre,
                                 "Two streams: centre of the clock-offset search (s), e.g. when the clocks have "
                                 "different epochs")
                     ->capture_default_str();
  fixed->needs(ref)->excludes(none)->excludes(search)->excludes(centre);
  none->needs(ref)->excludes(search)->excludes(centre);
  search->needs(ref);
  centre->needs(ref);
  cmd->add_option("--model", args.model_path, "Start from this model JSON instead of the affine nominal");
  cmd->add_option("--out", args.out_dir,
                  "Report directory (report.json, summary.txt, model, SVG plots); refused when it already holds "
                  "files, unless --force")
      ->required();
  cmd->add_flag("--force", args.force, "Replace the report files of an earlier audit in --out");
  cmd->add_option("--units", args.units, "Name of the reading's units, for the report")->capture_default_str();
  cmd->add_option("--heldout", args.heldout_fraction, "Fraction of the run (the later block) held out")
      ->check(Between(0.05, 0.9))
      ->capture_default_str();
  cmd->add_option("--max-causes", args.max_causes, "At most this many causes")
      ->check(Between(0, 20))
      ->capture_default_str();
  cmd->add_option("--taxels", args.taxels,
                  "Per-taxel CSV (t,reference,taxel_0..taxel_<N-1>): the taxel count expected; a missing column is "
                  "named (default: the highest taxel_<j> + 1)")
      ->check(Between(1, audit::kMaxTaxels))
      ->needs(csv);
  cmd->add_option("--blocks", args.blocks,
                  "Blocked hold-out: audit this many contiguous time blocks on their own too, so an effect that "
                  "appears only late is found (0 = off)")
      ->check(Between(0, 10))
      ->capture_default_str();
  cmd->add_flag("--quiet", args.quiet, "Do not print the summary");
  AddOutputFlags(cmd, &args.output, "report.json");
  cmd->footer(
      "Writes OUT/report.json, summary.txt, extended_model.json and SVG plots, and\n"
      "prints the summary. Examples:\n"
      "  tactforce simulate sensor --model client/examples/sensor_model.json --out /tmp/run\n"
      "  tactforce audit --csv /tmp/run/run.csv --out /tmp/audit\n"
      "  tactforce audit --reference client/examples/reference.csv --reading client/examples/reading.csv \\\n"
      "    --out /tmp/audit2 --json");
  return cmd;
}

int RunAuditCommand(const AuditArgs& args) {
  absl::StatusOr<audit::MeasuredData> data;
  if (!args.csv.empty()) {
    data = audit::ReadMeasuredCsv(args.csv, args.taxels);
  } else if (!args.reference_path.empty()) {
    audit::AlignOptions align;
    if (args.clock_offset_given) {
      align.mode = audit::ClockOffsetMode::kFixed;
      align.clock_offset = args.clock_offset;
    } else if (args.no_clock_offset) {
      align.mode = audit::ClockOffsetMode::kFixed;
      align.clock_offset = 0;
    } else {
      align.mode = audit::ClockOffsetMode::kEstimate;
      align.clock_offset = args.clock_offset_centre;
      align.max_clock_offset = args.max_clock_offset;
    }
    data = audit::ReadAndAlignStreams(args.reference_path, args.reading_path, align);
  } else {
    return ReportError(absl::InvalidArgumentError("give --csv FILE or --reference FILE --reading FILE"));
  }
  if (!data.ok()) return ReportError(data.status());
  audit::AuditOptions options;
  options.heldout_fraction = args.heldout_fraction;
  options.max_causes = args.max_causes;
  options.blocks = args.blocks;
  options.reading_units = args.units;
  if (!args.model_path.empty()) {
    absl::StatusOr<sim::SensorModel> model = sim::LoadSensorModel(args.model_path);
    if (!model.ok()) return ReportError(model.status());
    options.model = *model;
  }
  absl::StatusOr<audit::AuditReport> report = audit::RunAudit(*data, options);
  if (!report.ok()) return ReportError(report.status());
  // As `simulate --out`: an earlier report is never mixed with this one.
  if (absl::Status s = PrepareOutputDir(args.out_dir, args.force, audit::AuditReportFileNames(), "--out",
                                        "this audit's");
      !s.ok()) {
    return ReportError(s);
  }
  if (absl::Status s = audit::WriteAuditReport(*report, args.out_dir, args.csv); !s.ok()) {
    return ReportError(absl::InvalidArgumentError(absl::StrCat("--out: ", s.message())));
  }
  if (args.output.json()) {
    std::cout << audit::AuditReportJson(*report);
  } else if (!args.quiet) {
    std::cout << audit::FormatAuditSummary(*report);
  }
  std::cerr << "report written to " << args.out_dir << "/report.json\n";
  return std::cout ? kExitOk : kExitFailure;
}

CLI::App* AddSimulateSensorCommand(CLI::App& simulate, SimulateSensorArgs& args) {
  CLI::App* cmd = simulate.add_subcommand(
      "sensor", "Simulate a tactile fingertip against a reference force: run.csv + model.json");
  cmd->add_option("--model", args.model_path, "Sensor model JSON (absent: ideal sensor)");
  cmd->add_option("--profile", args.profile, "Force profile")
      ->check(CLI::IsMember({"press-release", "ramp", "random"}))
      ->capture_default_str();
  cmd->add_option("--seconds", args.seconds, "Duration (s)")->check(Between(0.1, 86400))->capture_default_str();
  cmd->add_option("--rate", args.rate, "Sample rate (Hz)")->check(Between(1, 1e5))->capture_default_str();
  cmd->add_option("--seed", args.seed, "Random seed")->capture_default_str();
  cmd->add_option("--out", args.out_dir, "Output directory (created; must be empty unless --force)")->required();
  cmd->add_flag("--force", args.force, "Replace the run.csv, fingertip.csv and model.json of an earlier run in --out");
  cmd->footer(
      "Writes OUT/run.csv (t,reference,reading), OUT/fingertip.csv and OUT/model.json. Example:\n"
      "  tactforce simulate sensor --model client/examples/sensor_model.json --out /tmp/run && \\\n"
      "    tactforce audit --csv /tmp/run/run.csv --out /tmp/audit");
  return cmd;
}

int RunSimulateSensor(const SimulateSensorArgs& args) {
  sim::SensorModel model;
  if (!args.model_path.empty()) {
    absl::StatusOr<sim::SensorModel> loaded = sim::LoadSensorModel(args.model_path);
    if (!loaded.ok()) return ReportError(loaded.status());
    model = *loaded;
  }
  absl::StatusOr<sim::Profile> profile = sim::ParseProfile(args.profile);
  if (!profile.ok()) return ReportError(profile.status());
  sim::SimOptions options;
  options.profile = *profile;
  options.seconds = args.seconds;
  options.rate = args.rate;
  options.seed = args.seed;
  if (absl::Status s = PrepareOutputDir(args.out_dir, args.force, {"run.csv", "fingertip.csv", "model.json"});
      !s.ok()) {
    return ReportError(s);
  }
  absl::StatusOr<sim::SimRun> run = sim::SimulateSensor(model, options);
  if (!run.ok()) return ReportError(run.status());
  if (absl::Status s = sim::WriteSimRun(*run, args.out_dir); !s.ok()) return ReportError(s);
  std::cerr << "wrote " << run->t.size() << " samples to " << args.out_dir
            << "/run.csv (+ fingertip.csv, model.json)\n";
  return kExitOk;
}

}  // namespace tactforce::cli
