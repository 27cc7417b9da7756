// tactforce: the command line. Registers every subcommand (plan, demo,
// health, load, estimate, friction, simulate friction|sensor|inertia, audit,
// experiment, inertia), parses the arguments (a parse error is one line and
// exit 2) and runs the chosen one; an escaping exception is exit 1.
#include <exception>
#include <iostream>
#include <string>

#include "CLI/CLI.hpp"
#include "audit_command.h"
#include "cli_common.h"
#include "cli_suggest.h"
#include "demo_command.h"
#include "estimate_command.h"
#include "experiment_command.h"
#include "health_command.h"
#include "inertia_command.h"
#include "load_command.h"
#include "plan_command.h"
#include "simulate_inertia_command.h"
#include "tactforce/api/version.h"

namespace {

int Main(int argc, char** argv) {
  using namespace tactforce::cli;

  CLI::App app{"tactforce: robust fingertip contact-force planning (GeoDEx)", "tactforce"};
  app.set_version_flag("--version", std::string("tactforce ") + tactforce::api::kVersion);
  app.require_subcommand(1);

  PlanArgs plan_args;
  CLI::App* plan = AddPlanCommand(app, plan_args);
  DemoArgs demo_args;
  CLI::App* demo = AddDemoCommand(app, demo_args);
  HealthArgs health_args;
  CLI::App* health = AddHealthCommand(app, health_args);
  LoadArgs load_args;
  CLI::App* load = AddLoadCommand(app, load_args);
  EstimateArgs estimate_args;
  CLI::App* estimate = AddEstimateCommand(app, estimate_args);
  FrictionArgs friction_args;
  CLI::App* friction = AddFrictionCommand(app, friction_args);
  CLI::App* simulate = app.add_subcommand("simulate", "Write simulated data sets with their truth");
  simulate->require_subcommand(1);
  SimulateFrictionArgs simulate_friction_args;
  CLI::App* simulate_friction = AddSimulateFrictionCommand(*simulate, simulate_friction_args);
  SimulateSensorArgs simulate_sensor_args;
  CLI::App* simulate_sensor = AddSimulateSensorCommand(*simulate, simulate_sensor_args);
  AuditArgs audit_args;
  CLI::App* audit = AddAuditCommand(app, audit_args);
  ExperimentArgs experiment_args;
  CLI::App* experiment = AddExperimentCommand(app, experiment_args);
  InertiaArgs inertia_args;
  CLI::App* inertia = AddInertiaCommand(app, inertia_args);
  SimulateInertiaArgs simulate_inertia_args;
  CLI::App* simulate_inertia = AddSimulateInertiaCommand(*simulate, simulate_inertia_args);

  // Set last: a subcommand copies its parent's footer when it is created,
  // and each has its own examples.
  app.footer(
      "Examples:\n"
      "  tactforce plan --local --request client/examples/sphere_pinch.json\n"
      "  cat client/examples/sphere_pinch.json | tactforce plan --local --request -\n"
      "  tactforce plan --server localhost:50051 --request client/examples/sphere_pinch.json\n"
      "  tactforce health --server localhost:50051\n"
      "  tactforce load --target localhost:50051 --rpc plan --concurrency 8 --duration 5\n"
      "  tactforce demo [--server localhost:50051]\n"
      "  tactforce simulate inertia --out sim/ && tactforce inertia --csv sim/inertia.csv --truth sim/truth.json\n"
      "Run 'tactforce COMMAND --help' for the options of a command.");
  if (argc <= 1) {  // bare `tactforce`: the command list
    std::cout << app.help();
    return kExitOk;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    const ArgumentHint hint = HintForArguments(app, argc, argv);
    std::string what = hint.message.empty() ? std::string(e.what()) : hint.message;
    for (char& c : what) {
      if (c == '\n') c = ' ';
    }
    std::cerr << "error: " << what << " (see " << hint.command_path << " --help)" << std::endl;
    return kExitBadInput;
  }

  if (plan->parsed()) return RunPlan(plan_args);
  if (demo->parsed()) return RunDemo(demo_args);
  if (health->parsed()) return RunHealth(health_args);
  if (load->parsed()) return RunLoadCommand(load_args);
  if (estimate->parsed()) return RunEstimate(estimate_args);
  if (friction->parsed()) return RunFriction(friction_args);
  if (simulate_friction->parsed()) return RunSimulateFriction(simulate_friction_args);
  if (simulate_sensor->parsed()) return RunSimulateSensor(simulate_sensor_args);
  if (audit->parsed()) return RunAuditCommand(audit_args);
  if (experiment->parsed()) return RunExperiment(experiment_args);
  if (inertia->parsed()) return RunInertia(inertia_args);
  if (simulate_inertia->parsed()) return RunSimulateInertia(simulate_inertia_args);
  std::cerr << "error: no command given (see tactforce --help)" << std::endl;
  return kExitBadInput;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return Main(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "error: internal: " << e.what() << std::endl;
    return tactforce::cli::kExitFailure;
  } catch (...) {
    std::cerr << "error: internal: unknown exception" << std::endl;
    return tactforce::cli::kExitFailure;
  }
}
