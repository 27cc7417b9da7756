// tactforce.v1.Info over the real server (started on an ephemeral loopback
// port by ServerTest): the version is the CMake project version, the build
// type the build's, the services exactly what reflection lists; and both
// binaries' --version print the same version.
#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tactforce/v1/info.grpc.pb.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

using ::testing::Contains;
using ::testing::ElementsAreArray;

// Straight from CMake (tests/server/CMakeLists.txt), not from version.h, so
// a generated header that drifted from project(VERSION) fails here.
constexpr char kProjectVersion[] = TACTFORCE_EXPECTED_VERSION;
constexpr char kBuildType[] = TACTFORCE_EXPECTED_BUILD_TYPE;

using InfoRpcTest = ServerTest;

grpc::Status GetServerInfo(const std::shared_ptr<grpc::Channel>& channel,
                           v1::ServerInfoResponse* response) {
  std::unique_ptr<v1::Info::Stub> stub = v1::Info::NewStub(channel);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  return stub->GetServerInfo(&context, v1::ServerInfoRequest(), response);
}

TEST_F(InfoRpcTest, VersionIsTheProjectVersion) {
  v1::ServerInfoResponse info;
  grpc::Status status = GetServerInfo(channel_, &info);
  ASSERT_TRUE(status.ok()) << Describe(status);
  EXPECT_EQ(info.version(), kProjectVersion);
  EXPECT_EQ(info.build_type(), kBuildType);
}

TEST_F(InfoRpcTest, ServicesAreWhatReflectionLists) {
  v1::ServerInfoResponse info;
  grpc::Status status = GetServerInfo(channel_, &info);
  ASSERT_TRUE(status.ok()) << Describe(status);
  const std::vector<std::string> services(info.services().begin(), info.services().end());
  EXPECT_TRUE(std::is_sorted(services.begin(), services.end()));
  for (const char* name : {"tactforce.v1.Planner", "tactforce.v1.Estimator", "tactforce.v1.Audit",
                           "tactforce.v1.Info", "grpc.health.v1.Health"}) {
    EXPECT_THAT(services, Contains(name));
  }
  absl::StatusOr<std::vector<std::string>> listed = ReflectionListServices(channel_);
  ASSERT_TRUE(listed.ok()) << listed.status();
  std::sort(listed->begin(), listed->end());
  EXPECT_THAT(services, ElementsAreArray(*listed));
}

TEST_F(InfoRpcTest, ReflectionAndHealthKnowInfo) {
  absl::StatusOr<std::vector<std::string>> files =
      ReflectionFilesContainingSymbol(channel_, "tactforce.v1.Info");
  ASSERT_TRUE(files.ok()) << files.status();
  EXPECT_THAT(*files, Contains("tactforce/v1/info.proto"));
  EXPECT_EQ(HealthCheck(channel_, "tactforce.v1.Info").value_or(-1), 1);  // SERVING
}

TEST(VersionFlagTest, BothBinariesPrintTheProjectVersion) {
  for (const std::string name : {"tactforce", "tactforce-server"}) {
    ProcessResult run = RunProcess({BinaryPath(name).string(), "--version"});
    ASSERT_EQ(run.exit_code, 0) << name << ": " << run.err;
    EXPECT_EQ(run.out, name + " " + kProjectVersion + "\n");
  }
}

}  // namespace
}  // namespace tactforce::testing
