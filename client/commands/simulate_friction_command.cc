// `tactforce simulate friction`: simulated probing trials (one CSV each)
// and truth.json.
#include "simulate_friction_command.h"

#include <iostream>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "cli_common.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/io/json.h"
#include "tactforce/io/text_file.h"

namespace tactforce::cli {

CLI::App* AddSimulateFrictionCommand(CLI::App& simulate, SimulateFrictionArgs& args) {
  CLI::App* cmd = simulate.add_subcommand(
      "friction", "Write simulated probing trials (CSV per trial) and truth.json");
  cmd->add_option("--mu", args.mu, "True static friction coefficient")
      ->check(Between(0.01, 10))
      ->capture_default_str();
  cmd->add_option("--trials", args.trials, "Number of trials")
      ->check(Between(1, 10000))
      ->capture_default_str();
  cmd->add_option("--noise", args.noise, "Force noise std. dev. per component (N)")
      ->check(AtLeast(0))
      ->capture_default_str();
  cmd->add_option("--rate", args.rate, "Sample rate (Hz)")
      ->check(Between(1, 1e5))
      ->capture_default_str();
  cmd->add_option("--ramp", args.ramp, "Normal-force ramp-down rate (N/s)")
      ->check(GreaterThan(0))
      ->capture_default_str();
  cmd->add_option("--tangential-force", args.tangential_force, "Held tangential force (N)")
      ->check(GreaterThan(0))
      ->capture_default_str();
  cmd->add_flag("--slip-flags", args.slip_flags, "Also write a slip column (0/1)");
  cmd->add_option("--seed", args.seed, "Random seed")->capture_default_str();
  cmd->add_option("--out", args.out_dir, "Output directory (created; must be empty unless --force)")
      ->required();
  cmd->add_flag("--force", args.force,
                "Replace the trial*.csv and truth.json of an earlier run in --out");
  cmd->footer(
      "Writes OUT/trial<i>.csv and OUT/truth.json. Example:\n"
      "  tactforce simulate friction --mu 0.3 --trials 10 --out /tmp/friction && \\\n"
      "    tactforce friction /tmp/friction/trial*.csv --normal 0,0,-1");
  return cmd;
}

int RunSimulateFriction(const SimulateFrictionArgs& args) {
  if (absl::Status s = PrepareOutputDir(args.out_dir, args.force, {"trial*.csv", "truth.json"});
      !s.ok()) {
    return ReportError(s);
  }
  estimator::FrictionSimOptions sim;
  sim.mu = args.mu;
  sim.trials = args.trials;
  sim.force_noise = args.noise;
  sim.rate = args.rate;
  sim.ramp = args.ramp;
  sim.tangential_force = args.tangential_force;
  sim.write_slip_flags = args.slip_flags;
  sim.seed = args.seed;
  const estimator::SimulatedFriction data = estimator::SimulateFriction(sim);
  for (size_t i = 0; i < data.trials.size(); ++i) {
    std::string csv = absl::StrCat("t,fx,fy,fz,px,py,pz", args.slip_flags ? ",slip" : "", "\n");
    for (const auto& s : data.trials[i].samples) {
      absl::StrAppendFormat(&csv, "%.6f,%.6f,%.6f,%.6f,%.8f,%.8f,%.8f", s.t, s.force.x(),
                            s.force.y(), s.force.z(), s.contact_point.x(), s.contact_point.y(),
                            s.contact_point.z());
      if (args.slip_flags) absl::StrAppend(&csv, ",", s.slip.value_or(false) ? 1 : 0);
      csv += "\n";
    }
    const std::string path = absl::StrCat(args.out_dir, "/trial", i, ".csv");
    if (absl::Status st = io::WriteTextFile(path, csv); !st.ok()) return ReportError(st);
  }
  io::JsonWriter truth;
  truth.BeginObject();
  truth.Field("mu", args.mu);
  truth.NumberArray("normal", {data.normal.x(), data.normal.y(), data.normal.z()});
  truth.NumberArray("slip_times", data.true_slip_time);
  truth.Field("force_noise", args.noise);
  truth.Field("rate", args.rate);
  truth.Field("ramp", args.ramp);
  truth.FieldInt("seed", static_cast<long long>(args.seed));
  truth.EndObject();
  if (absl::Status st = io::WriteTextFile(args.out_dir + "/truth.json", truth.str() + "\n");
      !st.ok())
    return ReportError(st);
  std::cerr << "wrote " << data.trials.size() << " trials and truth.json to " << args.out_dir
            << "\n";
  return kExitOk;
}

}  // namespace tactforce::cli
