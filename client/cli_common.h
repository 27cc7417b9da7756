// Exit codes and small I/O helpers shared by the subcommands.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "CLI/CLI.hpp"

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

// A picture's output path, checked before any work: empty is fine (no
// picture); otherwise an .svg name (tactforce draws SVG only; a .png name
// would get SVG bytes) that is not a directory, in a writable folder.
// Errors name `flag`: "--plot: 'p.png': ...".
absl::Status CheckPlotPath(const std::string& path, const std::string& flag = "--plot");

// Whole contents of `path`; "-" reads standard input. Errors name the path.
absl::StatusOr<std::string> ReadInput(const std::string& path,
                                      const std::string& flag = "--request");

// Output of every subcommand: a human table by default, JSON with --json;
// --format table|json is accepted as a synonym.
struct OutputFormat {
  bool json_flag = false;
  std::string format = "table";
  bool json() const { return json_flag || format == "json"; }
};
// Adds --json and --format; `json_what` says what the JSON is ("the
// PlanResponse").
void AddOutputFlags(CLI::App* cmd, OutputFormat* out, const std::string& json_what);

// Adds --seconds (0.1 s to a day) and --rate (1 Hz to 100 kHz) for a
// simulated recording; the defaults are the values already held.
void AddRecordingClockFlags(CLI::App* cmd, double* seconds, double* rate);

// Numeric flag checks; a failure is a usage error (exit 2) naming the flag:
// "--window: must be >= 1, got 0".
CLI::Validator AtLeast(double min);              // finite and >= min
CLI::Validator GreaterThan(double min);          // finite and > min
CLI::Validator Between(double min, double max);  // finite and in [min, max]

// Makes `dir` ready for a simulation's files: created when missing; when it
// already holds files, InvalidArgument naming `flag` unless `force`, which
// first removes only the files the simulation writes (names matching one of
// `patterns`, "*" a wildcard: "trial*.csv"), so an earlier run's files can
// never be mixed with the new ones. Other files are left alone.
// `whose` names those files in the refusal ("this simulation's files").
absl::Status PrepareOutputDir(const std::string& dir, bool force,
                              const std::vector<std::string>& patterns,
                              const std::string& flag = "--out",
                              const std::string& whose = "this simulation's");

// How an input is named in messages: its path, "<stdin>" for "-".
std::string InputName(const std::string& path);

// "x,y,z" (three finite numbers) as a vector; errors name the flag.
absl::StatusOr<Eigen::Vector3d> ParseVec3(const std::string& text, const std::string& flag);

// Prints "error: <message>" as one line on stderr and returns
// ExitCodeFor(status.code()). InvalidArgument, Unavailable and
// DeadlineExceeded messages are printed as they are; other codes are
// prefixed with their name ("error: INTERNAL: ...").
int ReportError(const absl::Status& status);

}  // namespace tactforce::cli
