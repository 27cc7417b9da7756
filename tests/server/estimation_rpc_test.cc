// The estimation and motion RPCs over the real server: each answer equals the
// in-process one (same api:: path), and bad requests name their field.
#include <gtest/gtest.h>

#include "tactforce/api/convert.h"
#include "tactforce/api/services.h"
#include "tactforce/estimator/friction.h"
#include "tactforce/planner/examples.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "request_builders.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

using EstimationRpcTest = ServerTest;

grpc::ClientContext* WithDeadline(grpc::ClientContext* c) {
  c->set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  return c;
}

TEST_F(EstimationRpcTest, EstimateForcesMatchesInProcess) {
  auto stub = v1::Estimator::NewStub(channel_);
  v1::EstimateRequest request = WrenchEstimateRequest();
  for (auto method : {v1::ESTIMATE_METHOD_PROJECTION, v1::ESTIMATE_METHOD_NORMAL_LSQ}) {
    request.set_method(method);
    grpc::ClientContext context;
    v1::EstimateResponse remote;
    ASSERT_TRUE(stub->EstimateForces(WithDeadline(&context), request, &remote).ok());
    absl::StatusOr<v1::EstimateResponse> local = api::HandleEstimate(request);
    ASSERT_TRUE(local.ok());
    EXPECT_EQ(remote.status(), v1::ESTIMATE_STATUS_OK);
    ASSERT_EQ(remote.forces_size(), 3);
    for (int i = 0; i < 3; ++i) {
      EXPECT_DOUBLE_EQ(remote.forces(i).x(), local->forces(i).x());
      EXPECT_DOUBLE_EQ(remote.forces(i).z(), local->forces(i).z());
    }
  }
  request.clear_readings();
  request.add_readings(1.0);
  grpc::ClientContext context;
  v1::EstimateResponse response;
  const grpc::Status bad = stub->EstimateForces(WithDeadline(&context), request, &response);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(bad.error_message().rfind("readings: expected 3", 0), 0u) << bad.error_message();
}

TEST_F(EstimationRpcTest, EstimateFrictionRecoversMu) {
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FrictionRequest request = SimulatedFrictionRequest(0.45, 4);
  grpc::ClientContext context;
  v1::FrictionResponse response;
  ASSERT_TRUE(stub->EstimateFriction(WithDeadline(&context), request, &response).ok());
  EXPECT_EQ(response.count(), 4);
  EXPECT_NEAR(response.median(), 0.45, 0.02);
  request.mutable_trials(1)->mutable_samples(5)->set_t(0.0);
  grpc::ClientContext context2;
  const grpc::Status bad = stub->EstimateFriction(WithDeadline(&context2), request, &response);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(bad.error_message(), "trials[1].samples[5].t: not increasing");
}

TEST_F(EstimationRpcTest, PlanTrajectoryAndProbe) {
  const v1::TrajectoryRequest request = LiftRequest(30);
  grpc::ClientContext context;
  v1::TrajectoryResponse remote;
  ASSERT_TRUE(stub_->PlanTrajectory(WithDeadline(&context), request, &remote).ok());
  EXPECT_EQ(remote.optimal_steps(), 30);
  absl::StatusOr<v1::TrajectoryResponse> local = api::HandleTrajectory(request);
  ASSERT_TRUE(local.ok());
  for (int k = 0; k < 30; ++k) {
    EXPECT_DOUBLE_EQ(remote.steps(k).forces(0).z(), local->steps(k).forces(0).z());
  }
  v1::TrajectoryRequest broken = request;
  broken.mutable_steps(4)->mutable_angular_velocity()->set_x(std::nan(""));
  grpc::ClientContext context2;
  const grpc::Status bad = stub_->PlanTrajectory(WithDeadline(&context2), broken, &remote);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_EQ(bad.error_message(), "steps[4].angular_velocity: not a finite vector");

  const v1::FrictionProbeRequest probe = ProbeRequest();
  grpc::ClientContext context3;
  v1::FrictionProbeResponse plan;
  ASSERT_TRUE(stub_->PlanFrictionProbe(WithDeadline(&context3), probe, &plan).ok());
  EXPECT_EQ(plan.times_size(), 21);
  EXPECT_EQ(plan.holding().optimal_steps(), 21);
}

}  // namespace
}  // namespace tactforce::testing

#include "tactforce/sim/simulate.h"
#include "tactforce/v1/audit.grpc.pb.h"

namespace tactforce::testing {
namespace {

// AuditModel with a 60 s deadline.
grpc::Status CallAudit(v1::Audit::Stub& stub, const v1::AuditRequest& request,
                       v1::AuditResponse* response) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  return stub.AuditModel(&context, request, response);
}

TEST_F(EstimationRpcTest, AuditModelNamesAHiddenThreshold) {
  sim::SensorModel model;
  model.noise = 0.02;
  model.effects.threshold = 0.3;
  v1::AuditRequest request = SimulatedAuditRequest(model, 15, 9);
  request.set_source("rpc-test");
  auto stub = v1::Audit::NewStub(channel_);
  v1::AuditResponse response;
  const grpc::Status status = CallAudit(*stub, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  EXPECT_FALSE(response.nominal_adequate());
  ASSERT_GE(response.causes_size(), 1);
  EXPECT_EQ(response.causes(0).effect(), "deadzone");
  EXPECT_GT(response.gain(), 0.0);
  request.mutable_samples()->DeleteSubrange(10, request.samples_size() - 10);
  const grpc::Status bad = CallAudit(*stub, request, &response);
  EXPECT_EQ(bad.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(bad.error_message().find("too few samples"), std::string::npos) << bad.error_message();
}

// The form of a two-form effect and its array parameters reach RPC clients
// as fields, not only inside report_json.
TEST_F(EstimationRpcTest, AuditModelReportsThePrandtlIshlinskiiForm) {
  sim::SensorModel model;
  model.noise = 0.01;
  model.effects.pi_thresholds = {0.0, 0.04, 0.12, 0.25};
  model.effects.pi_weights = {0.25, 0.25, 0.25, 0.25};
  const v1::AuditRequest request = SimulatedAuditRequest(model, 20, 11);
  auto stub = v1::Audit::NewStub(channel_);
  v1::AuditResponse response;
  const grpc::Status status = CallAudit(*stub, request, &response);
  ASSERT_TRUE(status.ok()) << status.error_message();
  ASSERT_GE(response.causes_size(), 1);
  const v1::AuditCause& cause = response.causes(0);
  EXPECT_EQ(cause.effect(), "hysteresis");
  EXPECT_EQ(cause.form(), "prandtl_ishlinskii");
  ASSERT_TRUE(cause.array_parameters().contains("pi_weights"));
  ASSERT_TRUE(cause.array_parameters().contains("pi_thresholds"));
  const v1::DoubleList& weights = cause.array_parameters().at("pi_weights");
  EXPECT_EQ(weights.values_size(), cause.array_parameters().at("pi_thresholds").values_size());
  double sum = 0;
  for (double w : weights.values()) {
    EXPECT_GE(w, 0.0);
    sum += w;
  }
  EXPECT_NEAR(sum, 1.0, 1e-9);
}

}  // namespace
}  // namespace tactforce::testing
