// `tactforce audit`: measured data from one CSV or two aligned streams,
// the audit through the Backend, its report directory and summary.
#include "audit_command.h"

#include <iostream>
#include <utility>

#include "absl/strings/str_cat.h"
#include "cli_common.h"
#include "tactforce/audit/audit.h"
#include "tactforce/audit/measured_data.h"
#include "tactforce/sim/sensor_model.h"
#include "tactforce/io/status_macros.h"
#include "tactforce/io/text_file.h"

namespace tactforce::cli {

namespace {

// The measured data: one CSV, or two streams with their clock-offset flags.
// Returns --csv (other flags depend on it).
CLI::Option* AddAuditInputFlags(CLI::App* cmd, AuditArgs& args) {
  auto* csv =
      cmd->add_option("--csv", args.csv,
                      "Measured data: t,reference,reading[,shear][,trial], or per taxel "
                      "t,reference,taxel_0,...,taxel_<N-1>[,reading][,shear][,trial]; - = stdin")
          ->type_name("FILE");
  auto* ref = cmd->add_option("--reference", args.reference_path,
                              "Reference stream: t,value[,shear]; - = stdin")
                  ->type_name("FILE");
  auto* reading =
      cmd->add_option("--reading", args.reading_path, "Reading stream: t,value; - = stdin")
          ->type_name("FILE");
  csv->excludes(ref)->excludes(reading);
  ref->needs(reading);
  reading->needs(ref);
  auto* fixed =
      cmd->add_option(
             "--clock-offset", args.clock_offset,
             "Two streams: fix the clock offset (reading clock minus reference clock, s) instead "
             "of estimating it; the sensor's delay is then audited")
          ->each([&args](const std::string&) { args.clock_offset_given = true; });
  auto* none = cmd->add_flag(
      "--no-clock-offset", args.no_clock_offset,
      "Two streams: no clock-offset estimation (offset 0; a clock offset then shows as 'delay')");
  auto* search =
      cmd->add_option(
             "--max-clock-offset", args.max_clock_offset,
             "Two streams: estimate the clock offset within +/- this (s; default estimation)")
          ->check(GreaterThan(0))
          ->capture_default_str();
  auto* centre =
      cmd->add_option(
             "--clock-offset-centre", args.clock_offset_centre,
             "Two streams: centre of the clock-offset search (s), e.g. when the clocks have "
             "different epochs")
          ->capture_default_str();
  fixed->needs(ref)->excludes(none)->excludes(search)->excludes(centre);
  none->needs(ref)->excludes(search)->excludes(centre);
  search->needs(ref);
  centre->needs(ref);
  return csv;
}

}  // namespace

CLI::App* AddAuditCommand(CLI::App& app, AuditArgs& args) {
  CLI::App* cmd = app.add_subcommand(
      "audit", "Show what the sensor model gets wrong on measured data, name the cause, extend it");
  CLI::Option* csv = AddAuditInputFlags(cmd, args);
  cmd->add_option("--model", args.model_path,
                  "Start from this model JSON instead of the affine nominal");
  cmd->add_option("--out", args.out_dir,
                  "Report directory (report.json, summary.txt, model, SVG plots); refused when it "
                  "already holds files, unless --force")
      ->required();
  cmd->add_flag("--force", args.force, "Replace the report files of an earlier audit in --out");
  cmd->add_option("--units", args.units, "Name of the reading's units, for the report")
      ->capture_default_str();
  cmd->add_option("--heldout", args.heldout_fraction,
                  "Fraction of the run (the later block) held out")
      ->check(Between(0.05, 0.9))
      ->capture_default_str();
  cmd->add_option("--max-causes", args.max_causes, "At most this many causes")
      ->check(Between(0, 20))
      ->capture_default_str();
  cmd->add_option("--taxels", args.taxels,
                  "Per-taxel CSV (t,reference,taxel_0..taxel_<N-1>): the taxel count expected; a "
                  "missing column is named (default: the highest taxel_<j> + 1)")
      ->check(Between(1, audit::kMaxTaxels))
      ->needs(csv);
  cmd->add_option("--blocks", args.blocks,
                  "Blocked hold-out: audit this many contiguous time blocks on their own too, so "
                  "an effect that appears only late is found (0 = off)")
      ->check(Between(0, 10))
      ->capture_default_str();
  cmd->add_flag("--quiet", args.quiet, "Do not print the summary");
  AddOutputFlags(cmd, &args.output, "report.json");
  AddBackendFlags(cmd, &args.backend, "Audit.AuditModel; the report folder then has no plots");
  cmd->footer(
      "Writes OUT/report.json, summary.txt, extended_model.json and SVG plots, and\n"
      "prints the summary. Examples:\n"
      "  tactforce simulate sensor --model client/examples/sensor_model.json --out /tmp/run\n"
      "  tactforce audit --csv /tmp/run/run.csv --out /tmp/audit\n"
      "  tactforce audit --reference client/examples/reference.csv --reading "
      "client/examples/reading.csv \\\n"
      "    --out /tmp/audit2 --json");
  return cmd;
}

namespace {

// The two streams aligned as the clock-offset flags say.
absl::StatusOr<audit::MeasuredData> ReadStreams(const AuditArgs& args) {
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
  return audit::ReadAndAlignStreams(args.reference_path, args.reading_path, align);
}

// The measured data (--csv, or --reference with --reading) and the options.
absl::StatusOr<AuditCall> BuildAuditCall(const AuditArgs& args) {
  AuditCall call;
  if (!args.csv.empty()) {
    TF_ASSIGN_OR_RETURN(call.data, audit::ReadMeasuredCsv(args.csv, args.taxels));
  } else if (!args.reference_path.empty()) {
    TF_ASSIGN_OR_RETURN(call.data, ReadStreams(args));
  } else {
    return absl::InvalidArgumentError("give --csv FILE or --reference FILE --reading FILE");
  }
  call.options.heldout_fraction = args.heldout_fraction;
  call.options.max_causes = args.max_causes;
  call.options.blocks = args.blocks;
  call.options.reading_units = args.units;
  if (!args.model_path.empty()) {
    TF_ASSIGN_OR_RETURN(call.options.model, sim::LoadSensorModel(args.model_path));
    TF_ASSIGN_OR_RETURN(call.model_json, io::ReadTextFile(args.model_path));
  }
  return call;
}

// The report folder: every file from the library's report (local), or the
// report, summary and extended model a server sends (no plots).
absl::Status WriteReportFiles(const AuditArgs& args, const AuditAnswer& answer) {
  if (answer.report) return audit::WriteAuditReport(*answer.report, args.out_dir, args.csv);
  for (const auto& [name, text] :
       {std::pair<const char*, const std::string*>{"report.json", &answer.report_json},
        {"summary.txt", &answer.summary},
        {"extended_model.json", &answer.extended_model_json}}) {
    TF_RETURN_IF_ERROR(io::WriteTextFile(args.out_dir + "/" + name, *text));
  }
  return absl::OkStatus();
}

}  // namespace

int RunAuditCommand(const AuditArgs& args) {
  absl::StatusOr<AuditCall> call = BuildAuditCall(args);
  if (!call.ok()) return ReportError(call.status());
  absl::StatusOr<AuditAnswer> answer = CallBackend(args.backend, &Backend::AuditModel, *call);
  if (!answer.ok()) return ReportError(answer.status());
  // As `simulate --out`: an earlier report is never mixed with this one.
  if (absl::Status s = PrepareOutputDir(args.out_dir, args.force, audit::AuditReportFileNames(),
                                        "--out", "this audit's");
      !s.ok()) {
    return ReportError(s);
  }
  if (absl::Status s = WriteReportFiles(args, *answer); !s.ok()) {
    return ReportError(absl::InvalidArgumentError(absl::StrCat("--out: ", s.message())));
  }
  if (args.output.json()) {
    std::cout << answer->report_json;
  } else if (!args.quiet) {
    std::cout << answer->summary;
  }
  std::cerr << "report written to " << args.out_dir << "/report.json\n";
  return std::cout ? kExitOk : kExitFailure;
}

}  // namespace tactforce::cli
