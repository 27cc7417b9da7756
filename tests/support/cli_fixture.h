// The one harness of the `tactforce` CLI tests: run the built binary
// ($TACTFORCE_BIN_DIR/tactforce, server/server_process.h's RunProcess)
// with arguments and standard input, a fixture with a private temporary
// directory and the bad-input checks, JSON and request helpers, and a
// fixture that runs one real tactforce-server for a test suite.
#pragma once

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <google/protobuf/struct.pb.h>
#include <gtest/gtest.h>

#include "absl/status/statusor.h"
#include "server/server_process.h"
#include "support/temp_dir.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::testing {

using CliRun = ProcessResult;

// $name when set and not empty, else `fallback`.
std::string EnvOr(const char* name, const char* fallback);
std::string ReadFile(const std::filesystem::path& path);
void WriteFile(const std::filesystem::path& path, const std::string& text);
std::vector<std::string> Lines(const std::string& text);

// Runs $TACTFORCE_BIN_DIR/tactforce with `args`; `stdin_text` is its
// standard input. Killed after `timeout`.
CliRun RunTactforce(const std::vector<std::string>& args, const std::string& stdin_text = "",
                    std::chrono::milliseconds timeout = std::chrono::minutes(10));
// The same with stdin /dev/null.
CliRun Tactforce(const std::vector<std::string>& args,
                 std::chrono::milliseconds timeout = std::chrono::seconds(30));

// "exit 3; stdout: ...; stderr: ..." for assertion messages.
std::string Describe(const CliRun& run);

// A bad-input run: exit 2, nothing on stdout, one "error: " line on stderr.
void ExpectBadInput(const CliRun& run);

// Flags that must each be refused: the flags, and what the error names.
using BadFlagCase = std::pair<std::vector<std::string>, std::string>;

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override;

  // Writes `text` to dir()/name and returns the path.
  std::filesystem::path Write(const std::string& name, const std::string& text);
  // Runs tactforce with `args`; `stdin_text` is its standard input.
  CliRun Tactforce(const std::vector<std::string>& args, const std::string& stdin_text = "");
  static void ExpectBadInput(const CliRun& run) { testing::ExpectBadInput(run); }
  // Runs `command` + each case's flags: ExpectBadInput, and the error
  // names the case's text.
  void ExpectBadFlags(const std::vector<std::string>& command,
                      const std::vector<BadFlagCase>& cases);

  const std::filesystem::path& dir() const { return dir_; }

  TempDir temp_{"tactforce_cli_test"};
  std::filesystem::path binary_ = BinaryPath("tactforce");
  std::filesystem::path dir_ = temp_.path();
};

// Parses a JSON object (strict: the whole text must be one JSON value).
absl::StatusOr<google::protobuf::Struct> ParseJsonObject(const std::string& text);
// A PlanResponse printed by `tactforce plan` (JSON).
absl::StatusOr<v1::PlanResponse> ParsePlanResponse(const std::string& text);

// A loopback port with nothing listening on it (bound, then closed).
int ClosedPort();

// Requests as JSON files' contents.
std::string ExampleRequestJson();  // client/examples/sphere_pinch.json
std::string RequestJson(const v1::PlanRequest& request);
// Seeded random grasp with `contacts` contacts.
v1::PlanRequest RandomRequest(uint64_t seed, int contacts, v1::Solver solver);

// Starts a tactforce-server with `flags`; fails the current test when it
// cannot.
std::unique_ptr<ServerProcess> StartServer(const std::vector<std::string>& flags = {});

// One server for all tests of a suite (started lazily, stopped at the end
// with SIGTERM; the exit code must be 0).
class RemoteCliTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite();
  static void TearDownTestSuite();
  void SetUp() override;

  static const std::string& address() { return server_->address(); }
  static ServerProcess& server() { return *server_; }

  TempDir dir_{"tactforce_cli_test"};

 private:
  static std::unique_ptr<ServerProcess> server_;
};

}  // namespace tactforce::testing

// The client tests (tests/cli) live in this namespace.
namespace tactforce::cli_testing {
using namespace ::tactforce::testing;  // NOLINT(build/namespaces)
}  // namespace tactforce::cli_testing
