// `tactforce simulate sensor`: the sensor-simulation library's run written
// to --out.
#include "simulate_sensor_command.h"

#include <iostream>

#include "cli_common.h"
#include "tactforce/sim/sensor_model.h"
#include "tactforce/sim/simulate.h"

namespace tactforce::cli {

CLI::App* AddSimulateSensorCommand(CLI::App& simulate, SimulateSensorArgs& args) {
  CLI::App* cmd = simulate.add_subcommand(
      "sensor", "Simulate a tactile fingertip against a reference force: run.csv + model.json");
  cmd->add_option("--model", args.model_path, "Sensor model JSON (absent: ideal sensor)");
  cmd->add_option("--profile", args.profile, "Force profile")
      ->check(CLI::IsMember({"press-release", "ramp", "random"}))
      ->capture_default_str();
  AddRecordingClockFlags(cmd, &args.seconds, &args.rate);
  cmd->add_option("--seed", args.seed, "Random seed")->capture_default_str();
  cmd->add_option("--out", args.out_dir, "Output directory (created; must be empty unless --force)")
      ->required();
  cmd->add_flag("--force", args.force,
                "Replace the run.csv, fingertip.csv and model.json of an earlier run in --out");
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
  if (absl::Status s =
          PrepareOutputDir(args.out_dir, args.force, {"run.csv", "fingertip.csv", "model.json"});
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
