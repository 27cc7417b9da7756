// The subcommands of `tactforce` as a table: main registers every entry
// under its group and runs the one that was parsed.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct CommandEntry {
  std::string group;  // "" = top level; else the name of a group entry
  // Adds the subcommand (its flags bound to arguments the entry owns).
  std::function<CLI::App*(CLI::App& parent)> add;
  // Runs it with the parsed arguments; empty for a group (e.g. `simulate`),
  // which only holds subcommands.
  std::function<int()> run;
};

// An entry for a command with arguments `Args`, `add` and `run`.
template <class Args>
CommandEntry MakeCommand(std::string group, CLI::App* (*add)(CLI::App&, Args&),
                         int (*run)(const Args&)) {
  auto args = std::make_shared<Args>();
  return CommandEntry{std::move(group),
                      [args, add](CLI::App& parent) { return add(parent, *args); },
                      [args, run] { return run(*args); }};
}

// Every command, in the order `tactforce --help` lists them; a group comes
// before its subcommands.
std::vector<CommandEntry> CommandTable();

}  // namespace tactforce::cli
