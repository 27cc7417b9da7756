// "Did you mean" for the command line: the first unknown command or flag in
// argv, found by walking argv down the CLI11 command tree (io/suggest's
// edit distance picks the candidates).
#pragma once

#include <string>

#include "CLI/CLI.hpp"

namespace tactforce::cli {

struct ArgumentHint {
  // "unknown command 'pln'; did you mean 'plan'?", "unknown flag '--lokal'
  // for 'tactforce plan'; did you mean '--local'?"; empty when argv has no
  // unknown command or flag (the parse error is about something else).
  std::string message;
  std::string command_path;  // "tactforce plan": where to look with --help
};

ArgumentHint HintForArguments(const CLI::App& app, int argc, const char* const* argv);

}  // namespace tactforce::cli
