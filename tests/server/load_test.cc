// 8 concurrent clients x 2,000 plans against one server, zero errors, every
// answer identical to the expected one.
//
// TACTFORCE_LOAD_SERVER_FLAGS (optional, space-separated) adds server flags,
// e.g. "--inline-max-contacts 0" to measure the all-pooled configuration.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "test_support.h"

namespace tactforce::testing {
namespace {

using Clock = std::chrono::steady_clock;

bool SameAnswer(const v1::PlanResponse& a, const v1::PlanResponse& b) {
  if (a.status() != b.status() || a.forces_size() != b.forces_size()) return false;
  for (int i = 0; i < a.forces_size(); ++i) {
    if (a.forces(i).x() != b.forces(i).x() || a.forces(i).y() != b.forces(i).y() ||
        a.forces(i).z() != b.forces(i).z())
      return false;
  }
  return true;
}

TEST(LoadTest, EightClientsTwoThousandPlansEachWithoutErrors) {
  constexpr int kClients = 8;
  constexpr int kPlansPerClient = 2000;

  std::vector<std::string> flags;
  if (const char* extra = std::getenv("TACTFORCE_LOAD_SERVER_FLAGS")) {
    std::istringstream words(extra);
    for (std::string w; words >> w;) flags.push_back(w);
  }
  std::string error;
  auto server = ServerProcess::Start(flags, &error);
  ASSERT_NE(server, nullptr) << error;

  // A realistic mix of fingertip grasps: 2-6 contacts, some infeasible,
  // plus the built-in wrench grasp.
  std::vector<v1::PlanRequest> requests = {WrenchRequest()};
  for (int i = 0; i < 63; ++i) {
    requests.push_back(RandomRequest(5000 + i, 2 + i % 5, v1::SOLVER_GEOMETRIC, true));
  }
  std::vector<v1::PlanResponse> expected(requests.size());
  {
    auto stub = v1::Planner::NewStub(Connect(server->address()));
    for (size_t i = 0; i < requests.size(); ++i) {
      grpc::Status status = CallPlan(*stub, requests[i], &expected[i]);
      ASSERT_TRUE(status.ok()) << Describe(status);
    }
  }

  std::atomic<int> errors{0}, mismatches{0};
  std::string first_error;
  std::mutex first_error_mu;
  const auto start = Clock::now();
  std::vector<std::thread> clients;
  for (int c = 0; c < kClients; ++c) {
    clients.emplace_back([&, c] {
      // One connection per client.
      grpc::ChannelArguments args;
      args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
      auto stub = v1::Planner::NewStub(
          Connect(server->address(), grpc::InsecureChannelCredentials(), args));
      for (int i = 0; i < kPlansPerClient; ++i) {
        const size_t k = (static_cast<size_t>(c) * 7 + i) % requests.size();
        v1::PlanResponse response;
        grpc::Status status = CallPlan(*stub, requests[k], &response, std::chrono::seconds(20));
        if (!status.ok()) {
          if (errors.fetch_add(1) == 0) {
            std::lock_guard<std::mutex> lock(first_error_mu);
            first_error = Describe(status);
          }
        } else if (!SameAnswer(response, expected[k])) {
          mismatches.fetch_add(1);
        }
      }
    });
  }
  for (std::thread& t : clients) t.join();
  const double seconds = std::chrono::duration<double>(Clock::now() - start).count();

  EXPECT_EQ(errors.load(), 0) << first_error;
  EXPECT_EQ(mismatches.load(), 0);
  const int total = kClients * kPlansPerClient;
  std::printf(
      "[ load     ] %d plans from %d clients in %.2f s: %.0f plans/s, %.0f us/plan "
      "per client\n",
      total, kClients, seconds, total / seconds, seconds * 1e6 / kPlansPerClient);
  ::testing::Test::RecordProperty("plans_per_second", static_cast<int>(total / seconds));
  EXPECT_EQ(server->Stop(), 0) << server->StderrText();
}

}  // namespace
}  // namespace tactforce::testing
