// Exit codes and small I/O helpers shared by the subcommands.
#pragma once

#include <string>

#include <Eigen/Core>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tactforce::cli {

// Process exit codes of `tactforce`, shared by every subcommand:
//   0  success: an answer was computed (a plan may still be infeasible or a
//      solver failure; its status says so), health is SERVING, a load run
//      had no failed call
//   1  internal or unexpected error (a bug, a server-side INTERNAL, any
//      gRPC code not listed below, e.g. RESOURCE_EXHAUSTED)
//   2  invalid input or argument: bad command line, unreadable file, bad
//      JSON, values the planner rejects (locally or INVALID_ARGUMENT from
//      the server; the message is the field path)
//   3  unavailable: the server cannot be reached (connection refused, TLS
//      handshake failure, no connection within --deadline-ms), or health
//      is not SERVING
//   4  deadline exceeded: connected, but no answer within --deadline-ms
enum ExitCode : int {
  kExitOk = 0,
  kExitFailure = 1,
  kExitBadInput = 2,
  kExitUnavailable = 3,
  kExitDeadline = 4,
};

// Exit code for a failed call with `code` (OK -> kExitOk).
int ExitCodeFor(absl::StatusCode code);

// Whole contents of `path`; "-" reads standard input. Errors name the path.
absl::StatusOr<std::string> ReadInput(const std::string& path,
                                      const std::string& flag = "--request");

// "x,y,z" (three finite numbers) as a vector; errors name the flag.
absl::StatusOr<Eigen::Vector3d> ParseVec3(const std::string& text, const std::string& flag);

// Prints "error: <message>" as one line on stderr and returns
// ExitCodeFor(status.code()). InvalidArgument, Unavailable and
// DeadlineExceeded messages are printed as they are; other codes are
// prefixed with their name ("error: INTERNAL: ...").
int ReportError(const absl::Status& status);

}  // namespace tactforce::cli
