// Helpers for the `tactforce` client tests: run the CLI binary, files in a
// private temporary directory, JSON checks, and a fixture that runs one real
// tactforce-server for a test suite (tests/server/server_process.h spawns it
// on 127.0.0.1:0 and reads the bound port).
#pragma once

#include <chrono>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <google/protobuf/struct.pb.h>
#include <gtest/gtest.h>

#include "absl/status/statusor.h"
#include "server/server_process.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::cli_testing {

using testing::ProcessResult;
using testing::ServerProcess;

// Runs $TACTFORCE_BIN_DIR/tactforce with `args` (stdin /dev/null).
ProcessResult Tactforce(const std::vector<std::string>& args,
                        std::chrono::milliseconds timeout = std::chrono::seconds(30));

// "exit 3; stdout: ...; stderr: ..." for assertion messages.
std::string Describe(const ProcessResult& run);

// A private directory, removed with the object.
class TempDir {
 public:
  TempDir();
  ~TempDir();
  // Writes `text` to dir/name and returns the path.
  std::string Write(const std::string& name, const std::string& text) const;
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }

 private:
  std::filesystem::path dir_;
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

  TempDir dir_;

 private:
  static std::unique_ptr<ServerProcess> server_;
};

}  // namespace tactforce::cli_testing
