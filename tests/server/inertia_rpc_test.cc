// Estimator.FitInertia over the real server: a client stream of sample
// batches gives the same answer as the in-process fit; a bad sample in a
// later message ends the call with INVALID_ARGUMENT naming it; options
// after the first message are rejected.
#include <gtest/gtest.h>

#include <memory>

#include "tactforce/api/inertia.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

using InertiaRpcTest = ServerTest;

inertia::SimulationResult Simulated(double force_variance) {
  inertia::SimulationOptions o;
  o.duration = 4.0;
  o.rate_hz = 100.0;
  o.noise.force_sigma = std::sqrt(force_variance);
  o.seed = 7;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(o);
  EXPECT_TRUE(r.ok()) << r.status();
  return *r;
}

// Streams `samples` in batches of `batch`, options in the first message.
grpc::Status Stream(v1::Estimator::Stub& stub, const inertia::InertiaSamples& samples,
                    const v1::InertiaFitOptions& options, int batch, v1::FitInertiaResponse* response,
                    int corrupt_index = -1, bool options_twice = false) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  std::unique_ptr<grpc::ClientWriter<v1::FitInertiaRequest>> writer = stub.FitInertia(&context, response);
  v1::FitInertiaRequest message;
  *message.mutable_options() = options;
  for (size_t i = 0; i < samples.samples.size(); ++i) {
    v1::InertiaSample* s = message.add_samples();
    *s = api::InertiaSampleToProto(samples.samples[i], samples.source);
    if (static_cast<int>(i) == corrupt_index) s->mutable_orientation()->Clear();  // zero quaternion
    if (message.samples_size() == batch || i + 1 == samples.samples.size()) {
      if (!writer->Write(message)) break;
      message.Clear();
      if (options_twice) *message.mutable_options() = options;
    }
  }
  writer->WritesDone();
  return writer->Finish();
}

TEST_F(InertiaRpcTest, StreamedFitEqualsInProcessFit) {
  const inertia::SimulationResult sim = Simulated(0.1);
  auto stub = v1::Estimator::NewStub(channel_);
  for (v1::InertiaMethod method : {v1::INERTIA_METHOD_BASELINE_LS, v1::INERTIA_METHOD_FACTOR_GRAPH,
                                   v1::INERTIA_METHOD_CONSTRAINED}) {
    v1::InertiaFitOptions options;
    options.set_method(method);
    *options.mutable_truth() = api::InertialParametersToProto(sim.truth.params);
    v1::FitInertiaResponse remote;
    const grpc::Status status = Stream(*stub, sim.samples, options, 64, &remote);
    ASSERT_TRUE(status.ok()) << status.error_message();
    absl::StatusOr<v1::FitInertiaResponse> local = api::FitInertiaSamples(sim.samples, options);
    ASSERT_TRUE(local.ok()) << local.status();
    EXPECT_EQ(remote.method(), method);
    EXPECT_EQ(remote.samples_received(), static_cast<int>(sim.samples.samples.size()));
    // Same computation, same thread-independent arithmetic: equal results.
    EXPECT_DOUBLE_EQ(remote.mass(), local->mass());
    EXPECT_DOUBLE_EQ(remote.com().y(), local->com().y());
    EXPECT_DOUBLE_EQ(remote.inertia().ixy(), local->inertia().ixy());
    EXPECT_EQ(remote.physically_consistent(), local->physically_consistent());
    ASSERT_TRUE(remote.has_errors());
    EXPECT_DOUBLE_EQ(remote.errors().paper_metric(), local->errors().paper_metric());
    EXPECT_LT(remote.errors().mass_percent(), 5.0) << v1::InertiaMethod_Name(method);
  }
}

TEST_F(InertiaRpcTest, BadSampleInALaterMessageIsNamed) {
  const inertia::SimulationResult sim = Simulated(0.0);
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FitInertiaResponse response;
  const grpc::Status status = Stream(*stub, sim.samples, v1::InertiaFitOptions(), 50, &response, 137);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("samples[137].orientation"), std::string::npos)
      << status.error_message();
}

TEST_F(InertiaRpcTest, OptionsOnlyInTheFirstMessage) {
  const inertia::SimulationResult sim = Simulated(0.0);
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FitInertiaResponse response;
  const grpc::Status status =
      Stream(*stub, sim.samples, v1::InertiaFitOptions(), 100, &response, -1, /*options_twice=*/true);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("options: only the first message"), std::string::npos)
      << status.error_message();
}

TEST_F(InertiaRpcTest, EmptyStreamAndBadOptionsAreInvalidArgument) {
  auto stub = v1::Estimator::NewStub(channel_);
  {
    grpc::ClientContext context;
    v1::FitInertiaResponse response;
    auto writer = stub->FitInertia(&context, &response);
    writer->WritesDone();
    const grpc::Status status = writer->Finish();
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
    EXPECT_NE(status.error_message().find("no samples"), std::string::npos) << status.error_message();
  }
  const inertia::SimulationResult sim = Simulated(0.0);
  v1::InertiaFitOptions options;
  options.mutable_noise()->set_force_sigma(-1.0);
  v1::FitInertiaResponse response;
  const grpc::Status status = Stream(*stub, sim.samples, options, 200, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("options.noise.force_sigma"), std::string::npos)
      << status.error_message();
}

class InertiaRpcLimitTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override { return {"--max-inertia-samples", "50"}; }
};

TEST_F(InertiaRpcLimitTest, StreamBeyondTheServersSampleLimitIsRejected) {
  const inertia::SimulationResult sim = Simulated(0.0);
  auto stub = v1::Estimator::NewStub(channel_);
  v1::FitInertiaResponse response;
  const grpc::Status status = Stream(*stub, sim.samples, v1::InertiaFitOptions(), 20, &response);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT);
  EXPECT_NE(status.error_message().find("more than 50 samples"), std::string::npos) << status.error_message();
}

}  // namespace
}  // namespace tactforce::testing
