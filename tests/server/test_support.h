// Helpers shared by the tactforce-server tests: requests, channels, the
// health and reflection probes, and a fixture that runs one server.
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <gtest/gtest.h>

#include "absl/status/statusor.h"
#include "server_process.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::testing {

// The planner's built-in "wrench-3f" example as a request.
v1::PlanRequest WrenchRequest(v1::Solver solver = v1::SOLVER_GEOMETRIC);
// A seeded random grasp with exactly `contacts` contacts (feasible by
// construction unless `allow_infeasible`).
v1::PlanRequest RandomRequest(uint64_t seed, int contacts, v1::Solver solver,
                              bool allow_infeasible = false);
// 60 contacts, SOLVER_IPOPT: ~150 ms of Ipopt on the dev box.
v1::PlanRequest SlowIpoptRequest(uint64_t seed = 60);

std::shared_ptr<grpc::Channel> Connect(
    const std::string& address,
    std::shared_ptr<grpc::ChannelCredentials> credentials = grpc::InsecureChannelCredentials(),
    grpc::ChannelArguments args = {});

// Unary Plan with a deadline.
grpc::Status CallPlan(v1::Planner::Stub& stub, const v1::PlanRequest& request,
                      v1::PlanResponse* response,
                      std::chrono::milliseconds deadline = std::chrono::seconds(30));

// "INVALID_ARGUMENT: contacts[2].normal: zero length"
std::string Describe(const grpc::Status& status);

// grpc.health.v1.Health/Check: the serving status (1 = SERVING,
// 2 = NOT_SERVING), or the RPC error.
absl::StatusOr<int> HealthCheck(const std::shared_ptr<grpc::Channel>& channel,
                                const std::string& service);

// grpc.reflection.v1alpha.ServerReflection: list_services, and the file
// names returned for file_containing_symbol.
absl::StatusOr<std::vector<std::string>> ReflectionListServices(
    const std::shared_ptr<grpc::Channel>& channel);
absl::StatusOr<std::vector<std::string>> ReflectionFilesContainingSymbol(
    const std::shared_ptr<grpc::Channel>& channel, const std::string& symbol);

// Runs one server per test (flags from server_flags()), with a connected
// Planner stub. TearDown stops it with SIGTERM and expects exit code 0.
class ServerTest : public ::testing::Test {
 protected:
  virtual std::vector<std::string> server_flags() const { return {}; }
  void SetUp() override;
  void TearDown() override;

  // Restarts with other flags (inside a test).
  void Restart(const std::vector<std::string>& flags);

  std::unique_ptr<ServerProcess> server_;
  std::shared_ptr<grpc::Channel> channel_;
  std::unique_ptr<v1::Planner::Stub> stub_;
};

}  // namespace tactforce::testing
