// The command table: one line per subcommand.
#include "command_table.h"

#include "audit_command.h"
#include "demo_command.h"
#include "estimate_command.h"
#include "experiment_command.h"
#include "friction_command.h"
#include "health_command.h"
#include "inertia_command.h"
#include "load_command.h"
#include "plan_command.h"
#include "simulate_friction_command.h"
#include "simulate_inertia_command.h"
#include "simulate_sensor_command.h"

namespace tactforce::cli {
namespace {

CLI::App* AddSimulateGroup(CLI::App& app) {
  CLI::App* simulate = app.add_subcommand("simulate", "Write simulated data sets with their truth");
  simulate->require_subcommand(1);
  return simulate;
}

}  // namespace

std::vector<CommandEntry> CommandTable() {
  return {
      MakeCommand("", AddPlanCommand, RunPlan),
      MakeCommand("", AddDemoCommand, RunDemo),
      MakeCommand("", AddHealthCommand, RunHealth),
      MakeCommand("", AddLoadCommand, RunLoadCommand),
      MakeCommand("", AddEstimateCommand, RunEstimate),
      MakeCommand("", AddFrictionCommand, RunFriction),
      CommandEntry{"", AddSimulateGroup, {}},
      MakeCommand("simulate", AddSimulateFrictionCommand, RunSimulateFriction),
      MakeCommand("simulate", AddSimulateSensorCommand, RunSimulateSensor),
      MakeCommand("", AddAuditCommand, RunAuditCommand),
      MakeCommand("", AddExperimentCommand, RunExperiment),
      MakeCommand("", AddInertiaCommand, RunInertia),
      MakeCommand("simulate", AddSimulateInertiaCommand, RunSimulateInertia),
  };
}

}  // namespace tactforce::cli
