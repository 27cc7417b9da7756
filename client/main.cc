// tactforce: the command line. Registers every subcommand of the command
// table (commands/command_table.h), parses the arguments (a parse error is
// one line and exit 2) and runs the chosen one; an escaping exception is
// exit 1.
#include <exception>
#include <iostream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "CLI/CLI.hpp"
#include "cli_common.h"
#include "cli_suggest.h"
#include "commands/command_table.h"
#include "tactforce/api/version.h"

namespace {

using namespace tactforce::cli;

// Set last: a subcommand copies its parent's footer when it is created,
// and each has its own examples.
constexpr char kFooter[] =
    "Examples:\n"
    "  tactforce plan --local --request client/examples/sphere_pinch.json\n"
    "  cat client/examples/sphere_pinch.json | tactforce plan --local --request -\n"
    "  tactforce plan --server localhost:50051 --request client/examples/sphere_pinch.json\n"
    "  tactforce health --server localhost:50051\n"
    "  tactforce load --target localhost:50051 --rpc plan --concurrency 8 --duration 5\n"
    "  tactforce demo [--server localhost:50051]\n"
    "  tactforce simulate inertia --out sim/ && tactforce inertia --csv sim/inertia.csv --truth "
    "sim/truth.json\n"
    "Run 'tactforce COMMAND --help' for the options of a command.";

// A parse error as one line naming the command whose --help to read.
int ReportParseError(const CLI::App& app, const CLI::ParseError& e, int argc, char** argv) {
  const ArgumentHint hint = HintForArguments(app, argc, argv);
  std::string what = hint.message.empty() ? std::string(e.what()) : hint.message;
  for (char& c : what) {
    if (c == '\n') c = ' ';
  }
  std::cerr << "error: " << what << " (see " << hint.command_path << " --help)" << std::endl;
  return kExitBadInput;
}

int Main(int argc, char** argv) {
  CLI::App app{"tactforce: robust fingertip contact-force planning (GeoDEx)", "tactforce"};
  app.set_version_flag("--version", std::string("tactforce ") + tactforce::api::kVersion);
  app.require_subcommand(1);

  const std::vector<CommandEntry> table = CommandTable();
  std::map<std::string, CLI::App*> groups;
  std::vector<std::pair<CLI::App*, const CommandEntry*>> commands;
  for (const CommandEntry& entry : table) {
    CLI::App* cmd = entry.add(entry.group.empty() ? app : *groups.at(entry.group));
    if (entry.run) {
      commands.emplace_back(cmd, &entry);
    } else {
      groups[cmd->get_name()] = cmd;
    }
  }
  app.footer(kFooter);
  if (argc <= 1) {  // bare `tactforce`: the command list
    std::cout << app.help();
    return kExitOk;
  }

  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    return ReportParseError(app, e, argc, argv);
  }
  for (const auto& [cmd, entry] : commands) {
    if (cmd->parsed()) return entry->run();
  }
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
