// The full request -> response path through the planner (api::HandlePlan,
// services.h; formerly handler.h's one-argument forwarder).
#include "tactforce/api/services.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>

#include "fixtures.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/inertia.h"
#include "tactforce/planner/examples.h"

namespace tactforce::api {
namespace {

using ::testing::HasSubstr;

TEST(HandlerTest, BuiltInGraspsAreOptimal) {
  for (const planner::ExampleGrasp& grasp : planner::BuiltInGrasps()) {
    SCOPED_TRACE(grasp.name);
    const v1::PlanRequest request =
        ToRequest(grasp.problem, grasp.options, planner::SolverKind::kGeometric);
    absl::StatusOr<v1::PlanResponse> response = HandlePlan(request);
    ASSERT_TRUE(response.ok()) << response.status();
    EXPECT_EQ(response->status(), v1::PLAN_STATUS_OPTIMAL) << response->message();
    EXPECT_EQ(response->forces_size(), request.contacts_size());
    EXPECT_EQ(response->normal_forces_size(), request.contacts_size());
    EXPECT_EQ(response->solver(), v1::SOLVER_GEOMETRIC);
    EXPECT_FALSE(response->has_cross_check());
  }
}

TEST(HandlerTest, CrossCheckFillsTheReport) {
  const planner::ExampleGrasp grasp = planner::BuiltInGrasps().front();
  const v1::PlanRequest request =
      ToRequest(grasp.problem, grasp.options, planner::SolverKind::kCrossCheck);
  absl::StatusOr<v1::PlanResponse> response = HandlePlan(request);
  ASSERT_TRUE(response.ok()) << response.status();
  ASSERT_TRUE(response->has_cross_check());
  EXPECT_TRUE(response->cross_check().agree());
  EXPECT_EQ(response->cross_check().ipopt_status(), v1::PLAN_STATUS_OPTIMAL);
}

v1::PlanRequest Lift(double max_normal_force) {
  // One fingertip under a 1 kg object's centre of mass, pushing up.
  v1::PlanRequest request;
  request.mutable_object()->set_mass(1.0);
  v1::Contact* c = request.add_contacts();
  c->set_name("palm");
  c->mutable_normal()->set_z(1.0);
  c->set_friction(0.5);
  c->set_max_normal_force(max_normal_force);
  return request;
}

TEST(HandlerTest, ZeroNormalIsRejectedNamingTheField) {
  v1::PlanRequest request = Lift(0.0);
  request.mutable_contacts(0)->clear_normal();
  absl::StatusOr<v1::PlanResponse> response = HandlePlan(request);
  ASSERT_FALSE(response.ok());
  EXPECT_EQ(response.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(response.status().message()), HasSubstr("contacts[0].normal"));
}

TEST(HandlerTest, UnknownEnumIsRejectedBeforePlanning) {
  v1::PlanRequest request = Lift(0.0);
  request.set_solver(static_cast<v1::Solver>(9));
  absl::StatusOr<v1::PlanResponse> response = HandlePlan(request);
  ASSERT_FALSE(response.ok());
  EXPECT_EQ(response.status().message(), "solver: unknown value 9");
}

TEST(HandlerTest, InfeasibilityIsAnAnswerNotAnError) {
  absl::StatusOr<v1::PlanResponse> response = HandlePlan(Lift(1.0));  // needs 9.81 N
  ASSERT_TRUE(response.ok()) << response.status();
  EXPECT_EQ(response->status(), v1::PLAN_STATUS_INFEASIBLE);
  EXPECT_FALSE(response->message().empty());

  response = HandlePlan(Lift(0.0));  // unbounded: feasible
  ASSERT_TRUE(response.ok()) << response.status();
  EXPECT_EQ(response->status(), v1::PLAN_STATUS_OPTIMAL) << response->message();
  ASSERT_EQ(response->forces_size(), 1);
  EXPECT_NEAR(response->forces(0).z(), 9.81, 1e-6);
}

}  // namespace
}  // namespace tactforce::api

namespace tactforce::api {
namespace {

// Issue 16: a motion's work and its answer's size are bounded before any
// step is solved (a 3,000-step, 64-contact request used 67 s of CPU and then
// could not be sent).
TEST(HandlerTest, TrajectoryWorkAndResponseSizeAreBoundedUpFront) {
  const planner::ExampleGrasp grasp = planner::BuiltInGrasps().front();
  v1::TrajectoryRequest request;
  *request.mutable_plan() =
      ToRequest(grasp.problem, grasp.options, planner::SolverKind::kGeometric);
  for (int k = 0; k < 100; ++k) request.add_steps();
  const int contacts = static_cast<int>(grasp.problem.contacts.size());
  CallLimits limits;
  ASSERT_TRUE(HandleTrajectory(request, limits).ok());

  limits.max_trajectory_work = 100 * contacts * grasp.options.cone_sides - 1;
  absl::StatusOr<v1::TrajectoryResponse> r = HandleTrajectory(request, limits);
  ASSERT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(r.status().message()), ::testing::StartsWith("steps: 100 steps with "));
  EXPECT_THAT(std::string(r.status().message()), ::testing::HasSubstr("--max-trajectory-work"));

  limits = CallLimits{};
  limits.max_response_bytes = 1000;
  r = HandleTrajectory(request, limits);
  ASSERT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(r.status().message()), ::testing::HasSubstr("--max-message-bytes"));
  // The estimate is an upper bound of what is sent.
  limits.max_response_bytes = 0;
  r = HandleTrajectory(request, limits);
  ASSERT_TRUE(r.ok());
  EXPECT_LE(static_cast<int64_t>(r->ByteSizeLong()), 100 * 40 + 100 * contacts * 60);

  const v1::FrictionProbeRequest probe =
      fixtures::ProbeRequest(request.plan(), 1000);  // 2,501 steps
  limits = CallLimits{};
  limits.max_trajectory_work = 1000;
  absl::StatusOr<v1::FrictionProbeResponse> p = HandleFrictionProbe(probe, limits);
  ASSERT_EQ(p.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(p.status().message()),
              ::testing::StartsWith("sample_rate: 2501 probe steps"));
}

// Messages follow the proto paths; options are named one by one.
TEST(HandlerTest, FrictionOptionsAreNamedOneByOne) {
  v1::FrictionRequest request;
  v1::FrictionTrial* trial = request.add_trials();
  trial->mutable_normal()->set_z(1);
  for (int k = 0; k < 5; ++k) trial->add_samples()->set_t(k);
  request.set_window(0);
  absl::StatusOr<v1::FrictionResponse> r = HandleFriction(request);
  EXPECT_EQ(r.status().message(), "window: must be >= 1 sample (got 0)");
  request.clear_window();
  request.set_slip_distance(-1);
  r = HandleFriction(request);
  EXPECT_EQ(r.status().message(), "slip_distance: must be finite and > 0 m (got -1)");
}

v1::AuditRequest RampAudit(int n) {
  v1::AuditRequest request;
  for (int k = 0; k < n; ++k) {
    v1::AuditSample* s = request.add_samples();
    s->set_t(0.01 * k);
    s->set_reference(std::sin(0.1 * k) + 1.5);
    s->set_reading(2 * s->reference() + 0.1);
  }
  return request;
}

TEST(HandlerTest, AuditNamesSamplesByTheirPathAndBoundsTheirNumber) {
  v1::AuditRequest request = RampAudit(100);
  request.mutable_samples(7)->set_reference(std::nan(""));
  EXPECT_EQ(HandleAudit(request).status().message(), "samples[7].reference: not a finite number");
  request = RampAudit(100);
  CallLimits limits;
  limits.max_audit_samples = 99;
  EXPECT_EQ(
      HandleAudit(request, limits).status().message(),
      "samples: 100 samples exceed the limit of 99 per request (the server's --max-audit-samples)");
  for (int k = 0; k < 100; ++k) request.mutable_samples(k)->set_reading(1.0);
  EXPECT_EQ(HandleAudit(request).status().message(),
            "samples[*].reading is constant (1): the sensor does not respond; nothing to audit");
}

TEST(HandlerTest, AuditAndFrictionStopWhenInterrupted) {
  CallLimits limits;
  const CallState state{[] { return true; }};
  const absl::Status audit = HandleAudit(RampAudit(200), limits, state).status();
  EXPECT_EQ(audit.code(), absl::StatusCode::kCancelled) << audit;
  EXPECT_THAT(std::string(audit.message()), HasSubstr("interrupted"));
  v1::FrictionRequest request;
  v1::FrictionTrial* trial = request.add_trials();
  trial->mutable_normal()->set_z(1);
  for (int k = 0; k < 5; ++k) trial->add_samples()->set_t(k);
  EXPECT_EQ(HandleFriction(request, limits, state).status().message(),
            "interrupted after 0 of 1 trials");
}

TEST(HandlerTest, InertiaCountsPastIntRangeAreNamedNotWrapped) {
  inertia::InertiaSamples samples;
  v1::InertiaFitOptions options;
  options.set_savitzky_golay_window(3'000'000'000u);
  absl::StatusOr<v1::FitInertiaResponse> r = FitInertiaSamples(samples, options);
  EXPECT_EQ(r.status().message(),
            "options.savitzky_golay_window: 3000000000 is out of range (at most 2147483647)");
}

TEST(HandlerTest, FitInertiaNamesTheWrenchPath) {
  InertiaStream stream;
  v1::FitInertiaRequest message;
  for (int k = 0; k < 60; ++k) {
    v1::InertiaSample* s = message.add_samples();
    s->set_t(0.01 * k);
    s->mutable_orientation()->set_w(1);
    s->mutable_wrench()->mutable_force()->set_z(k == 42 ? std::nan("") : -9.81);
  }
  ASSERT_TRUE(stream.Add(message).ok());
  EXPECT_EQ(FitInertiaSamples(stream.samples(), stream.options()).status().message(),
            "samples[42].wrench.force: not finite");
}

}  // namespace
}  // namespace tactforce::api
