// tactforce: plan fingertip contact forces from the command line.
#include <exception>
#include <iostream>
#include <string>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "demo_command.h"
#include "plan_command.h"

#ifndef TACTFORCE_VERSION
#define TACTFORCE_VERSION "unknown"
#endif

namespace {

int Main(int argc, char** argv) {
  using namespace tactforce::cli;

  CLI::App app{"tactforce: robust fingertip contact-force planning (GeoDEx)", "tactforce"};
  app.set_version_flag("--version", std::string("tactforce ") + TACTFORCE_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Examples:\n"
      "  tactforce plan --local --request client/examples/sphere_pinch.json --format table\n"
      "  cat request.json | tactforce plan --local --request -\n"
      "  tactforce demo\n"
      "Run 'tactforce COMMAND --help' for the options of a command.");

  PlanArgs plan_args;
  CLI::App* plan = AddPlanCommand(app, plan_args);
  DemoArgs demo_args;
  CLI::App* demo = AddDemoCommand(app, demo_args);

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    for (char& c : what) {
      if (c == '\n') c = ' ';
    }
    std::cerr << "error: " << what << " (see tactforce --help)" << std::endl;
    return kExitBadInput;
  }

  if (plan->parsed()) return RunPlan(plan_args);
  if (demo->parsed()) return RunDemo(demo_args);
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
