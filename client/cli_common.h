// Exit codes and small I/O helpers shared by the subcommands.
#pragma once

#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tactforce::cli {

// Process exit codes of `tactforce`.
enum ExitCode : int {
  kExitOk = 0,        // an answer was computed (optimal, infeasible or solver failure)
  kExitFailure = 1,   // unexpected internal error
  kExitBadInput = 2,  // bad command line, unreadable file, bad JSON, invalid values
};

// Whole contents of `path`; "-" reads standard input. Errors name the path.
absl::StatusOr<std::string> ReadInput(const std::string& path);

// Prints "error: <message>" as one line on stderr and returns the exit code
// for `status` (kExitBadInput for InvalidArgument, else kExitFailure).
int ReportError(const absl::Status& status);

}  // namespace tactforce::cli
