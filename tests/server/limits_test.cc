// Resource bounds an unauthenticated client cannot exceed (issue 16), each
// against the real server with a small limit: streams admitted up to
// --max-streams, idle streams ended after --stream-idle-timeout-ms, the
// FitInertia sample budget shared across streams (--max-inflight-samples),
// the per-call work limit (--solve-timeout-ms) on a long trajectory, the
// AuditModel sample limit, and reflection turned off (--reflection=false).
#include <gtest/gtest.h>

#include <chrono>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "gmock/gmock.h"
#include "request_builders.h"
#include "tactforce/api/inertia.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "tactforce/v1/info.grpc.pb.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;
using ReaderWriter = grpc::ClientReaderWriter<v1::PlanRequest, v1::PlanResponse>;

class ResourceLimitsTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override {
    return {"--max-streams",          "2",   "--stream-idle-timeout-ms", "600",
            "--max-inflight-samples", "300", "--solve-timeout-ms",       "100",
            "--max-audit-samples",    "500", "--reflection=false"};
  }
};

// An open PlanStream that has answered one request (so it is admitted).
struct OpenStream {
  grpc::ClientContext context;
  std::unique_ptr<ReaderWriter> stream;
};

std::unique_ptr<OpenStream> OpenPlanStream(v1::Planner::Stub& stub) {
  auto s = std::make_unique<OpenStream>();
  s->context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  s->stream = stub.PlanStream(&s->context);
  v1::PlanResponse response;
  if (!s->stream->Write(WrenchRequest()) || !s->stream->Read(&response)) return nullptr;
  return s;
}

TEST_F(ResourceLimitsTest, StreamsBeyondMaxStreamsAreRefusedAndIdleOnesEnded) {
  std::unique_ptr<OpenStream> first = OpenPlanStream(*stub_);
  std::unique_ptr<OpenStream> second = OpenPlanStream(*stub_);
  ASSERT_NE(first, nullptr);
  ASSERT_NE(second, nullptr);

  // A third stream is refused at once; unary calls still work.
  grpc::ClientContext context;
  auto third = stub_->PlanStream(&context);
  third->Write(WrenchRequest());
  v1::PlanResponse ignored;
  EXPECT_FALSE(third->Read(&ignored));
  const grpc::Status refused = third->Finish();
  EXPECT_EQ(refused.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(refused);
  EXPECT_THAT(refused.error_message(), HasSubstr("--max-streams"));
  v1::PlanResponse unary;
  EXPECT_TRUE(CallPlan(*stub_, WrenchRequest(), &unary).ok());

  // Both open streams now idle: each is ended with UNAVAILABLE naming the
  // flag within the timeout plus the reaper's 1 s period (and some slack).
  const auto start = Clock::now();
  for (OpenStream* s : {first.get(), second.get()}) {
    EXPECT_FALSE(s->stream->Read(&ignored));
    const grpc::Status idle = s->stream->Finish();
    EXPECT_EQ(idle.error_code(), grpc::StatusCode::UNAVAILABLE) << Describe(idle);
    EXPECT_THAT(idle.error_message(), HasSubstr("request 1: stream idle for more than 600 ms"));
    EXPECT_THAT(idle.error_message(), HasSubstr("--stream-idle-timeout-ms"));
  }
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(10));

  // Their slots are free again.
  EXPECT_NE(OpenPlanStream(*stub_), nullptr);
}

inertia::InertiaSamples FewSamples(int n) {
  inertia::SimulationOptions o;
  o.duration = n / 100.0;
  o.rate_hz = 100.0;
  o.seed = 3;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(o);
  EXPECT_TRUE(r.ok()) << r.status();
  inertia::InertiaSamples samples = r->samples;
  samples.samples.resize(std::min<size_t>(samples.samples.size(), n));
  return samples;
}

TEST_F(ResourceLimitsTest, FitInertiaSamplesShareOneBudgetAndAreReleased) {
  auto estimator = v1::Estimator::NewStub(channel_);
  // Stream A holds 200 samples and waits (not half-closed).
  grpc::ClientContext holder_context;
  v1::FitInertiaResponse holder_response;
  auto holder = estimator->FitInertia(&holder_context, &holder_response);
  const inertia::InertiaSamples two_hundred = FewSamples(200);
  v1::FitInertiaRequest message;
  v1::InertiaFitOptions least_squares;  // fast: well within the work limit
  least_squares.set_method(v1::INERTIA_METHOD_BASELINE_LS);
  *message.mutable_options() = least_squares;
  for (const auto& s : two_hundred.samples)
    *message.add_samples() = api::InertiaSampleToProto(s, two_hundred.source);
  ASSERT_TRUE(holder->Write(message));
  // Let the server take them in before the second stream arrives.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));

  // Stream B's 150 samples would pass the budget of 300.
  v1::FitInertiaResponse response;
  const grpc::Status over =
      StreamInertia(*estimator, FewSamples(150), least_squares, 150, &response);
  EXPECT_EQ(over.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(over);
  EXPECT_THAT(over.error_message(), HasSubstr("hold 200 samples and this message brings 150"));
  EXPECT_THAT(over.error_message(), HasSubstr("--max-inflight-samples"));

  // Once A is done (a fit within the work limit), B fits.
  holder->WritesDone();
  const grpc::Status held = holder->Finish();
  EXPECT_TRUE(held.ok()) << Describe(held);
  const grpc::Status after =
      StreamInertia(*estimator, FewSamples(150), least_squares, 150, &response);
  EXPECT_TRUE(after.ok()) << Describe(after);
  EXPECT_EQ(response.samples_received(), 150);
}

TEST_F(ResourceLimitsTest, LongTrajectoryStopsAtTheWorkLimit) {
  // 100 Ipopt steps (each ~10-30 ms) take far longer than 100 ms.
  v1::TrajectoryRequest request = LiftRequest(100);
  request.mutable_plan()->set_solver(v1::SOLVER_IPOPT);
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  v1::TrajectoryResponse response;
  const auto start = Clock::now();
  const grpc::Status status = stub_->PlanTrajectory(&context, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(status);
  EXPECT_THAT(status.error_message(),
              HasSubstr("limit of 100 ms of work per call (--solve-timeout-ms)"));
  EXPECT_THAT(status.error_message(), HasSubstr(" of 100 steps"));
  EXPECT_LT(Clock::now() - start, std::chrono::seconds(5));
  // A short one still fits in the limit.
  grpc::ClientContext short_context;
  EXPECT_TRUE(stub_->PlanTrajectory(&short_context, LiftRequest(20), &response).ok());
}

TEST_F(ResourceLimitsTest, AuditSamplesAreLimitedAndReflectionIsOff) {
  sim::SensorModel model;
  v1::AuditRequest request = SimulatedAuditRequest(model, 15, 4);
  ASSERT_GT(request.samples_size(), 500);
  auto audit = v1::Audit::NewStub(channel_);
  grpc::ClientContext context;
  v1::AuditResponse response;
  const grpc::Status status = audit->AuditModel(&context, request, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << Describe(status);
  EXPECT_THAT(status.error_message(), HasSubstr("samples: "));
  EXPECT_THAT(status.error_message(),
              HasSubstr("limit of 500 per request (the server's --max-audit-samples)"));

  // No reflection service, and Info does not list one.
  EXPECT_FALSE(ReflectionListServices(channel_).ok());
  auto info = v1::Info::NewStub(channel_);
  grpc::ClientContext info_context;
  v1::ServerInfoResponse served;
  ASSERT_TRUE(info->GetServerInfo(&info_context, v1::ServerInfoRequest(), &served).ok());
  EXPECT_THAT(served.services(),
              ::testing::Not(::testing::Contains("grpc.reflection.v1alpha.ServerReflection")));
  EXPECT_THAT(served.services(), ::testing::Contains("tactforce.v1.Audit"));
}

}  // namespace
}  // namespace tactforce::testing
