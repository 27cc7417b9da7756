// tactforce.v1.Planner/Plan against the real server: answers, the status
// codes of bad requests, deadlines, limits, health and reflection.
#include <cmath>
#include <functional>
#include <limits>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tactforce/api/convert.h"
#include "tactforce/planner/solver.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

using ::testing::Contains;
using ::testing::HasSubstr;
using ::testing::StartsWith;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

// The answer of the planner library, in-process, for comparison.
v1::PlanResponse LocalPlan(const v1::PlanRequest& request) {
  absl::StatusOr<api::PlanCall> call = api::FromProto(request);
  EXPECT_TRUE(call.ok()) << call.status();
  absl::StatusOr<planner::PlanResult> result =
      planner::Plan(call->problem, call->options, call->solver);
  EXPECT_TRUE(result.ok()) << result.status();
  return api::ToProto(*result);
}

void ExpectSameForces(const v1::PlanResponse& a, const v1::PlanResponse& b, double tolerance) {
  ASSERT_EQ(a.forces_size(), b.forces_size());
  for (int i = 0; i < a.forces_size(); ++i) {
    EXPECT_NEAR(a.forces(i).x(), b.forces(i).x(), tolerance) << "contact " << i;
    EXPECT_NEAR(a.forces(i).y(), b.forces(i).y(), tolerance) << "contact " << i;
    EXPECT_NEAR(a.forces(i).z(), b.forces(i).z(), tolerance) << "contact " << i;
  }
}

using PlannerRpcTest = ServerTest;

TEST_F(PlannerRpcTest, PlanReturnsTheLibrarysForces) {
  const v1::PlanRequest request = WrenchRequest();
  v1::PlanResponse response;
  grpc::Status status = CallPlan(*stub_, request, &response);
  ASSERT_TRUE(status.ok()) << Describe(status);
  EXPECT_EQ(response.status(), v1::PLAN_STATUS_OPTIMAL) << response.message();
  EXPECT_EQ(response.solver(), v1::SOLVER_GEOMETRIC);
  ASSERT_EQ(response.forces_size(), 3);
  ASSERT_EQ(response.normal_forces_size(), 3);
  ExpectSameForces(response, LocalPlan(request), 1e-12);
  // The fingers hold the 0.3 kg wrench: forces sum to +m g along z.
  double fz = 0;
  for (const v1::Vec3& f : response.forces()) fz += f.z();
  EXPECT_NEAR(fz, 0.3 * 9.81, 1e-6);
}

TEST_F(PlannerRpcTest, EverySolverAnswers) {
  v1::PlanResponse geometric;
  ASSERT_TRUE(CallPlan(*stub_, WrenchRequest(v1::SOLVER_GEOMETRIC), &geometric).ok());
  for (v1::Solver solver : {v1::SOLVER_UNSPECIFIED, v1::SOLVER_IPOPT, v1::SOLVER_CROSS_CHECK}) {
    SCOPED_TRACE(v1::Solver_Name(solver));
    v1::PlanRequest request = WrenchRequest();
    request.set_solver(solver);
    v1::PlanResponse response;
    grpc::Status status = CallPlan(*stub_, request, &response);
    ASSERT_TRUE(status.ok()) << Describe(status);
    EXPECT_EQ(response.status(), v1::PLAN_STATUS_OPTIMAL) << response.message();
    EXPECT_EQ(response.solver(), solver == v1::SOLVER_UNSPECIFIED ? v1::SOLVER_GEOMETRIC : solver);
    ExpectSameForces(response, geometric, 1e-4);
    if (solver == v1::SOLVER_CROSS_CHECK) {
      EXPECT_TRUE(response.cross_check().agree());
    }
  }
}

TEST_F(PlannerRpcTest, LargeGeometricRequestsUseThePoolAndMatch) {
  // 20 contacts > --inline-max-contacts (8): solved on a worker.
  const v1::PlanRequest request = RandomRequest(7, 20, v1::SOLVER_GEOMETRIC);
  v1::PlanResponse response;
  grpc::Status status = CallPlan(*stub_, request, &response);
  ASSERT_TRUE(status.ok()) << Describe(status);
  EXPECT_EQ(response.status(), v1::PLAN_STATUS_OPTIMAL) << response.message();
  ExpectSameForces(response, LocalPlan(request), 1e-12);
}

struct BadRequest {
  std::string name;
  std::function<void(v1::PlanRequest&)> mutate;
  std::string message_prefix;  // the field path (and start of the reason)
};

// Bad fields of the contacts.
std::vector<BadRequest> BadContactRequests() {
  return {
      {"no contacts", [](auto& r) { r.clear_contacts(); }, "contacts: at least one contact"},
      {"zero normal", [](auto& r) { r.mutable_contacts(2)->mutable_normal()->Clear(); },
       "contacts[2].normal: zero length"},
      {"NaN normal", [](auto& r) { r.mutable_contacts(0)->mutable_normal()->set_x(kNaN); },
       "contacts[0].normal: not a finite vector"},
      {"infinite position", [](auto& r) { r.mutable_contacts(1)->mutable_position()->set_z(kInf); },
       "contacts[1].position: not a finite vector"},
      {"negative friction", [](auto& r) { r.mutable_contacts(1)->set_friction(-0.1); },
       "contacts[1].friction: must be >= 0"},
      {"NaN friction", [](auto& r) { r.mutable_contacts(0)->set_friction(kNaN); },
       "contacts[0].friction: not a finite number"},
      {"negative sigma", [](auto& r) { r.mutable_contacts(2)->set_sigma(-1); },
       "contacts[2].sigma: must be >= 0"},
      {"negative min force", [](auto& r) { r.mutable_contacts(0)->set_min_normal_force(-1); },
       "contacts[0].min_normal_force: must be >= 0"},
      {"negative max force", [](auto& r) { r.mutable_contacts(1)->set_max_normal_force(-2); },
       "contacts[1].max_normal_force: must be >= 0"},
      {"min above max",
       [](auto& r) {
         r.mutable_contacts(0)->set_min_normal_force(5);
         r.mutable_contacts(0)->set_max_normal_force(2);
       },
       "contacts[0].min_normal_force: exceeds max_normal_force"},
      {"unknown contact kind",
       [](auto& r) { r.mutable_contacts(1)->set_kind(static_cast<v1::ContactKind>(7)); },
       "contacts[1].kind: unknown value 7"},
  };
}

// Bad fields of the object, the wrench and the solve; limits; pooled requests.
std::vector<BadRequest> BadProblemRequests() {
  return {
      {"negative mass", [](auto& r) { r.mutable_object()->set_mass(-1); },
       "object.mass: must be >= 0"},
      {"NaN mass", [](auto& r) { r.mutable_object()->set_mass(kNaN); },
       "object.mass: not a finite number"},
      {"infinite com", [](auto& r) { r.mutable_object()->mutable_com()->set_y(-kInf); },
       "object.com: not a finite vector"},
      {"NaN gravity", [](auto& r) { r.mutable_object()->mutable_gravity()->set_z(kNaN); },
       "object.gravity: not a finite vector"},
      {"infinite external force",
       [](auto& r) { r.mutable_external_wrench()->mutable_force()->set_x(kInf); },
       "external_wrench.force: not a finite vector"},
      {"NaN external torque",
       [](auto& r) { r.mutable_external_wrench()->mutable_torque()->set_y(kNaN); },
       "external_wrench.torque: not a finite vector"},
      {"unknown cone", [](auto& r) { r.set_cone(static_cast<v1::ConeModel>(9)); },
       "cone: unknown value 9"},
      {"cone sides 2", [](auto& r) { r.set_cone_sides(2); }, "cone_sides: must be in 3..64"},
      {"cone sides 65", [](auto& r) { r.set_cone_sides(65); }, "cone_sides: must be in 3..64"},
      {"cone sides 4e9", [](auto& r) { r.set_cone_sides(4'000'000'000u); },
       "cone_sides: must be in 3..64"},
      {"negative confidence", [](auto& r) { r.set_confidence(-1); },
       "confidence: must be in 0..1000 (got -1)"},
      {"NaN confidence", [](auto& r) { r.set_confidence(kNaN); },
       "confidence: must be in 0..1000 (got nan)"},
      // Found by the plan_json fuzzer: OPTIMAL with an infinite objective.
      {"huge confidence", [](auto& r) { r.set_confidence(7.5e250); },
       "confidence: must be in 0..1000 (got 7.5e+250)"},
      {"unknown solver", [](auto& r) { r.set_solver(static_cast<v1::Solver>(42)); },
       "solver: unknown value 42"},
      {"exact cone, geometric solver", [](auto& r) { r.set_cone(v1::CONE_MODEL_EXACT); },
       "cone: CONE_MODEL_EXACT is only solved by SOLVER_IPOPT"},
      {"65 contacts (server --max-contacts 64)",
       [](auto& r) {
         while (r.contacts_size() < 65) *r.add_contacts() = r.contacts(0);
       },
       "contacts: 65 contacts exceed the limit of 64"},
      // Requests bound for the worker pool are validated before queueing.
      {"zero normal, IPOPT",
       [](auto& r) {
         r.set_solver(v1::SOLVER_IPOPT);
         r.mutable_contacts(2)->mutable_normal()->Clear();
       },
       "contacts[2].normal: zero length"},
      {"negative friction, CROSS_CHECK",
       [](auto& r) {
         r.set_solver(v1::SOLVER_CROSS_CHECK);
         r.mutable_contacts(1)->set_friction(-3);
       },
       "contacts[1].friction: must be >= 0"},
      {"bad contact 15 of 20 (pooled geometric)",
       [](auto& r) {
         r = RandomRequest(3, 20, v1::SOLVER_GEOMETRIC);
         r.mutable_contacts(15)->set_sigma(-0.5);
       },
       "contacts[15].sigma: must be >= 0"},
      {"exact cone, 20 contacts (pooled geometric)",
       [](auto& r) {
         r = RandomRequest(3, 20, v1::SOLVER_GEOMETRIC);
         r.set_cone(v1::CONE_MODEL_EXACT);
       },
       "cone: CONE_MODEL_EXACT is only solved by SOLVER_IPOPT"},
  };
}

std::vector<BadRequest> BadRequests() {
  std::vector<BadRequest> all = BadContactRequests();
  for (BadRequest& bad : BadProblemRequests()) all.push_back(std::move(bad));
  return all;
}

TEST_F(PlannerRpcTest, BadRequestsAreInvalidArgumentNamingTheField) {
  const std::vector<BadRequest> table = BadRequests();
  ASSERT_GE(table.size(), 20u);
  const v1::PlanRequest good = WrenchRequest();
  for (const BadRequest& bad : table) {
    SCOPED_TRACE(bad.name);
    v1::PlanRequest request = good;
    bad.mutate(request);
    v1::PlanResponse response;
    grpc::Status status = CallPlan(*stub_, request, &response);
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << Describe(status);
    EXPECT_THAT(status.error_message(), StartsWith(bad.message_prefix));
    // ... and the server goes on serving.
    v1::PlanResponse ok;
    status = CallPlan(*stub_, good, &ok);
    ASSERT_TRUE(status.ok()) << Describe(status);
    EXPECT_EQ(ok.status(), v1::PLAN_STATUS_OPTIMAL);
  }
}

TEST_F(PlannerRpcTest, InfeasibleGraspIsOkWithInfeasibleStatus) {
  for (v1::Solver solver : {v1::SOLVER_GEOMETRIC, v1::SOLVER_IPOPT}) {
    SCOPED_TRACE(v1::Solver_Name(solver));
    // Frictionless fingers pushing sideways cannot hold the wrench up.
    v1::PlanRequest request = WrenchRequest(solver);
    for (v1::Contact& c : *request.mutable_contacts()) c.set_friction(0.0);
    v1::PlanResponse response;
    grpc::Status status = CallPlan(*stub_, request, &response);
    ASSERT_TRUE(status.ok()) << Describe(status);
    EXPECT_EQ(response.status(), v1::PLAN_STATUS_INFEASIBLE);
    EXPECT_FALSE(response.message().empty());
    EXPECT_EQ(response.forces_size(), 0);
  }
}

TEST_F(PlannerRpcTest, OversizeMessageIsResourceExhausted) {
  v1::PlanRequest request = WrenchRequest();
  request.mutable_contacts(0)->set_name(std::string(5 << 20, 'x'));  // > 4 MiB default
  v1::PlanResponse response;
  grpc::Status status = CallPlan(*stub_, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(status);
  ASSERT_TRUE(CallPlan(*stub_, WrenchRequest(), &response).ok());
}

TEST_F(PlannerRpcTest, HealthIsServing) {
  EXPECT_EQ(HealthCheck(channel_, "").value_or(-1), 1);  // SERVING
  EXPECT_EQ(HealthCheck(channel_, "tactforce.v1.Planner").value_or(-1), 1);
  EXPECT_EQ(HealthCheck(channel_, "tactforce.v1.Nope").status().code(),
            absl::StatusCode::kNotFound);
}

TEST_F(PlannerRpcTest, ReflectionListsThePlanner) {
  absl::StatusOr<std::vector<std::string>> services = ReflectionListServices(channel_);
  ASSERT_TRUE(services.ok()) << services.status();
  EXPECT_THAT(*services, Contains("tactforce.v1.Planner"));
  EXPECT_THAT(*services, Contains("grpc.health.v1.Health"));
  absl::StatusOr<std::vector<std::string>> files =
      ReflectionFilesContainingSymbol(channel_, "tactforce.v1.Planner");
  ASSERT_TRUE(files.ok()) << files.status();
  EXPECT_THAT(*files, Contains("tactforce/v1/planner.proto"));
}

TEST_F(PlannerRpcTest, DeadlineExceededOnSlowIpoptSolve) {
  v1::PlanResponse response;
  grpc::Status status =
      CallPlan(*stub_, SlowIpoptRequest(), &response, std::chrono::milliseconds(1));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << Describe(status);
  // The server is fine afterwards.
  status = CallPlan(*stub_, WrenchRequest(v1::SOLVER_IPOPT), &response);
  ASSERT_TRUE(status.ok()) << Describe(status);
  EXPECT_EQ(response.status(), v1::PLAN_STATUS_OPTIMAL);
}

class OneWorkerTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override {
    return {"--workers", "1", "--queue", "1", "--log-level", "info"};
  }
};

TEST_F(OneWorkerTest, QueuedSolvePastItsDeadlineIsNotStarted) {
  // A slow solve occupies the only worker; a second request with a short
  // deadline waits in the queue and must be dropped, not solved.
  std::thread slow([&] {
    v1::PlanResponse response;
    grpc::Status status = CallPlan(*stub_, SlowIpoptRequest(1), &response);
    EXPECT_TRUE(status.ok()) << Describe(status);
  });
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  v1::PlanResponse response;
  grpc::Status status =
      CallPlan(*stub_, SlowIpoptRequest(2), &response, std::chrono::milliseconds(40));
  EXPECT_EQ(status.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << Describe(status);
  slow.join();
  EXPECT_TRUE(server_->WaitForStderr("deadline exceeded before the solve started",
                                     std::chrono::seconds(10)))
      << server_->StderrText();
}

TEST_F(OneWorkerTest, FullQueueIsResourceExhausted) {
  // 1 worker + 1 queue slot: of 6 simultaneous slow solves, the rest are
  // turned away at once instead of queueing.
  constexpr int kCalls = 6;
  std::vector<grpc::Status> statuses(kCalls);
  std::vector<std::thread> threads;
  for (int i = 0; i < kCalls; ++i) {
    threads.emplace_back([&, i] {
      v1::PlanResponse response;
      statuses[i] = CallPlan(*stub_, SlowIpoptRequest(10 + i), &response);
    });
  }
  for (std::thread& t : threads) t.join();
  int ok = 0, exhausted = 0;
  for (const grpc::Status& s : statuses) {
    if (s.ok()) {
      ++ok;
    } else {
      EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
      EXPECT_THAT(s.error_message(), HasSubstr("retry later"));
      ++exhausted;
    }
  }
  EXPECT_GE(ok, 1);
  EXPECT_GE(exhausted, 1);
  // Geometric requests of <= 8 contacts are solved inline, not queued.
  v1::PlanResponse response;
  EXPECT_TRUE(CallPlan(*stub_, WrenchRequest(), &response).ok());
}

TEST_F(OneWorkerTest, OneLogLinePerRequestAtInfo) {
  v1::PlanResponse response;
  ASSERT_TRUE(CallPlan(*stub_, WrenchRequest(), &response).ok());
  v1::PlanRequest bad = WrenchRequest(v1::SOLVER_IPOPT);
  bad.mutable_contacts(2)->mutable_normal()->Clear();
  (void)CallPlan(*stub_, bad, &response);
  EXPECT_TRUE(server_->WaitForStderr(
      "rpc=Plan code=OK solver=GEOMETRIC contacts=3 where=inline plan_status=OPTIMAL solve_us=",
      std::chrono::seconds(5)))
      << server_->StderrText();
  EXPECT_TRUE(server_->WaitForStderr("rpc=Plan code=INVALID_ARGUMENT solver=IPOPT contacts=3",
                                     std::chrono::seconds(5)))
      << server_->StderrText();
  EXPECT_THAT(server_->StderrText(), HasSubstr("message=\"contacts[2].normal: zero length\""));
}

class LimitsTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override {
    return {"--max-contacts", "4", "--solve-timeout-ms", "1", "--max-message-bytes", "65536"};
  }
};

TEST_F(LimitsTest, FlagsSetTheLimits) {
  v1::PlanResponse response;
  // --max-contacts 4
  grpc::Status status = CallPlan(*stub_, RandomRequest(5, 5, v1::SOLVER_GEOMETRIC), &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << Describe(status);
  EXPECT_EQ(status.error_message(), "contacts: 5 contacts exceed the limit of 4");
  // --solve-timeout-ms 1 caps Ipopt: an answer, with SOLVER_FAILURE.
  status = CallPlan(*stub_, RandomRequest(5, 4, v1::SOLVER_IPOPT), &response);
  ASSERT_TRUE(status.ok()) << Describe(status);
  if (response.status() != v1::PLAN_STATUS_OPTIMAL) {  // may finish within 1 ms of CPU
    EXPECT_EQ(response.status(), v1::PLAN_STATUS_SOLVER_FAILURE);
    EXPECT_THAT(response.message(), HasSubstr("time limit"));
  }
  // --max-message-bytes 65536
  v1::PlanRequest big = WrenchRequest();
  big.mutable_contacts(0)->set_name(std::string(100'000, 'x'));
  status = CallPlan(*stub_, big, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(status);
  status = CallPlan(*stub_, WrenchRequest(), &response);
  EXPECT_TRUE(status.ok()) << Describe(status);
}

}  // namespace
}  // namespace tactforce::testing
