// Requests from a careless or hostile client (issue 23), each against the
// real server: bytes that cannot be parsed (unary, and inside PlanStream and
// FitInertia streams), status messages that would echo too much, a
// PlanStream client that never reads, the FitInertia byte budget, and the
// Ipopt lane that keeps geometric work moving while Ipopt is busy.
#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <grpcpp/grpcpp.h>
#include <grpcpp/impl/client_unary_call.h>
#include <grpcpp/support/byte_buffer.h>
#include <grpcpp/support/sync_stream.h>

#include "gmock/gmock.h"
#include "request_builders.h"
#include "tactforce/api/inertia.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/v1/audit.grpc.pb.h"
#include "tactforce/v1/estimator.grpc.pb.h"
#include "tactforce/v1/info.grpc.pb.h"
#include "test_support.h"
#include "support/test_seed.h"

namespace tactforce::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;
using Clock = std::chrono::steady_clock;
using grpc::internal::RpcMethod;

// A length-delimited field declaring more bytes than follow, so no message
// parses from it: field 2 declaring 4 GiB (the reproducer), or a
// field and length drawn from `rng`.
std::string Corrupt(std::mt19937_64* rng = nullptr) {
  if (rng == nullptr) return std::string("\x12\xff\xff\xff\x0f", 5);
  const int field = std::uniform_int_distribution<int>(1, 15)(*rng);
  uint64_t length = std::uniform_int_distribution<uint64_t>(64, uint64_t{1} << 32)(*rng);
  std::string out(1, static_cast<char>(field << 3 | 2));
  for (; length >= 0x80; length >>= 7) out += static_cast<char>(0x80 | (length & 0x7f));
  out += static_cast<char>(length);
  return out + "abc";
}

grpc::ByteBuffer Bytes(const std::string& bytes) {
  grpc::Slice slice(bytes);
  return grpc::ByteBuffer(&slice, 1);
}

template <class Message>
grpc::ByteBuffer Bytes(const Message& message) {
  return Bytes(message.SerializeAsString());
}

void SetDeadline(grpc::ClientContext* context, std::chrono::seconds seconds) {
  context->set_deadline(std::chrono::system_clock::now() + seconds);
}

grpc::Status RawUnary(const std::shared_ptr<grpc::Channel>& channel, const std::string& method,
                      const grpc::ByteBuffer& request) {
  grpc::ClientContext context;
  SetDeadline(&context, std::chrono::seconds(30));
  grpc::ByteBuffer response;
  return grpc::internal::BlockingUnaryCall<grpc::ByteBuffer, grpc::ByteBuffer>(
      channel.get(), RpcMethod(method.c_str(), RpcMethod::NORMAL_RPC), &context, request,
      &response);
}

class HardeningTest : public ServerTest {};

TEST_F(HardeningTest, UnaryRequestsThatCannotBeParsedAreInvalidArgumentNamingTheType) {
  const std::vector<std::pair<std::string, std::string>> methods = {
      {"/tactforce.v1.Planner/Plan", "tactforce.v1.PlanRequest"},
      {"/tactforce.v1.Planner/PlanTrajectory", "tactforce.v1.TrajectoryRequest"},
      {"/tactforce.v1.Planner/PlanFrictionProbe", "tactforce.v1.FrictionProbeRequest"},
      {"/tactforce.v1.Estimator/EstimateForces", "tactforce.v1.EstimateRequest"},
      {"/tactforce.v1.Estimator/EstimateFriction", "tactforce.v1.FrictionRequest"},
      {"/tactforce.v1.Audit/AuditModel", "tactforce.v1.AuditRequest"},
      {"/tactforce.v1.Info/GetServerInfo", "tactforce.v1.ServerInfoRequest"}};
  // The bytes, then a corrupt field drawn per run after a valid request.
  std::mt19937_64 rng(::tactforce::testing::GtestSeed());
  const std::string good = WrenchRequest().SerializeAsString();
  for (const auto& [method, type] : methods) {
    const grpc::Status status = RawUnary(channel_, method, Bytes(Corrupt()));
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT)
        << method << ": " << Describe(status);
    EXPECT_EQ(status.error_message(), "request cannot be parsed as " + type) << method;
  }
  for (const auto& [method, type] : methods) {
    const grpc::Status status = RawUnary(channel_, method, Bytes(good + Corrupt(&rng)));
    EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT)
        << method << ": " << Describe(status);
    EXPECT_EQ(status.error_message(), "request cannot be parsed as " + type) << method;
  }
  // A method that does not exist is still UNIMPLEMENTED.
  EXPECT_EQ(RawUnary(channel_, "/tactforce.v1.Planner/NoSuchMethod", Bytes(good)).error_code(),
            grpc::StatusCode::UNIMPLEMENTED);
  // And the same bytes uncorrupted are served.
  EXPECT_TRUE(RawUnary(channel_, "/tactforce.v1.Planner/Plan", Bytes(good)).ok());
}

TEST_F(HardeningTest, PlanStreamWithACorruptRequestEndsNamingItsIndex) {
  grpc::ClientContext context;
  SetDeadline(&context, std::chrono::seconds(30));
  // The internal factories return owning raw pointers.
  std::unique_ptr<grpc::ClientReaderWriter<grpc::ByteBuffer, grpc::ByteBuffer>> stream(
      grpc::internal::ClientReaderWriterFactory<grpc::ByteBuffer, grpc::ByteBuffer>::Create(
          channel_.get(), RpcMethod("/tactforce.v1.Planner/PlanStream", RpcMethod::BIDI_STREAMING),
          &context));
  // The corrupt message's position is drawn per run (2..4).
  std::mt19937_64 rng(::tactforce::testing::GtestSeed());
  const int corrupt = std::uniform_int_distribution<int>(2, 4)(rng);
  int responses = 0;
  for (int i = 0; i < 6; ++i) {
    if (!stream->Write(i == corrupt ? Bytes(Corrupt(&rng)) : Bytes(WrenchRequest()))) break;
    grpc::ByteBuffer response;
    if (!stream->Read(&response)) break;
    v1::PlanResponse parsed;
    std::vector<grpc::Slice> slices;
    ASSERT_TRUE(response.Dump(&slices).ok());
    std::string bytes;
    for (const grpc::Slice& s : slices)
      bytes.append(reinterpret_cast<const char*>(s.begin()), s.size());
    ASSERT_TRUE(parsed.ParseFromString(bytes));
    EXPECT_EQ(parsed.status(), v1::PLAN_STATUS_OPTIMAL);
    ++responses;
  }
  stream->WritesDone();
  const grpc::Status status = stream->Finish();
  EXPECT_EQ(responses, corrupt);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << Describe(status);
  EXPECT_EQ(status.error_message(), "request " + std::to_string(corrupt) +
                                        ": cannot be parsed as tactforce.v1.PlanRequest");
}

// FitInertia messages of `per_message` samples from a seeded simulation
// (in-hand contacts).
std::vector<v1::FitInertiaRequest> InertiaMessages(int messages, int per_message) {
  inertia::SimulationOptions sim;
  sim.rate_hz = 100.0;
  sim.duration = messages * per_message / sim.rate_hz;
  sim.seed = 23;
  absl::StatusOr<inertia::SimulationResult> result = inertia::SimulateInertia(sim);
  EXPECT_TRUE(result.ok()) << result.status();
  std::vector<v1::FitInertiaRequest> out(messages);
  if (!result.ok()) return out;
  const std::vector<inertia::InertiaSample>& samples = result->samples.samples;
  for (int i = 0; i < messages * per_message && i < static_cast<int>(samples.size()); ++i) {
    *out[i / per_message].add_samples() =
        api::InertiaSampleToProto(samples[i], result->samples.source);
  }
  return out;
}

grpc::Status StreamRaw(const std::shared_ptr<grpc::Channel>& channel,
                       const std::vector<grpc::ByteBuffer>& messages) {
  grpc::ClientContext context;
  SetDeadline(&context, std::chrono::seconds(60));
  grpc::ByteBuffer response;
  std::unique_ptr<grpc::ClientWriter<grpc::ByteBuffer>> writer(
      grpc::internal::ClientWriterFactory<grpc::ByteBuffer>::Create(
          channel.get(),
          RpcMethod("/tactforce.v1.Estimator/FitInertia", RpcMethod::CLIENT_STREAMING), &context,
          &response));
  for (const grpc::ByteBuffer& m : messages) {
    if (!writer->Write(m)) break;
  }
  writer->WritesDone();
  return writer->Finish();
}

TEST_F(HardeningTest, FitInertiaWithACorruptMessageIsNeverAPartialFit) {
  const std::vector<v1::FitInertiaRequest> messages = InertiaMessages(4, 300);
  std::vector<grpc::ByteBuffer> good, corrupted;
  for (const auto& m : messages) good.push_back(Bytes(m));
  // The whole stream fits.
  EXPECT_TRUE(StreamRaw(channel_, good).ok());
  std::mt19937_64 rng(::tactforce::testing::GtestSeed());
  const int corrupt = std::uniform_int_distribution<int>(1, 3)(rng);
  corrupted = good;
  corrupted[corrupt] = Bytes(corrupt == 2 ? Corrupt() : Corrupt(&rng));
  const grpc::Status status = StreamRaw(channel_, corrupted);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << Describe(status);
  EXPECT_EQ(status.error_message(), "message " + std::to_string(corrupt) +
                                        ": cannot be parsed as tactforce.v1.FitInertiaRequest");
}

TEST_F(HardeningTest, LongEchoedInputKeepsItsCodeWithABoundedMessage) {
  // The mesh's name is echoed in its error; 20 KB of it would overflow the
  // client's 8 KiB header limit (RESOURCE_EXHAUSTED) if sent whole.
  std::vector<v1::FitInertiaRequest> messages = InertiaMessages(1, 100);
  v1::MeshInput* mesh = messages[0].mutable_options()->mutable_mesh();
  mesh->set_name(std::string(20'000, 'n') + ".stl");
  mesh->set_format("stl");
  mesh->set_data("");
  const grpc::Status status = StreamRaw(channel_, {Bytes(messages[0])});
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT)
      << status.error_message().size();
  EXPECT_LE(status.error_message().size(), 2048u);
  EXPECT_THAT(status.error_message(), HasSubstr("bytes cut]"));
}

class StreamBoundsTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override {
    return {"--max-streams",        "1",       "--stream-idle-timeout-ms", "500",
            "--max-inflight-bytes", "2000000", "--max-fit-bytes",          "1000000"};
  }
};

// A PlanStream whose client sends but never reads fills its flow-control
// window; its write then blocks, and the reaper must end it like an idle
// one, freeing the only --max-streams slot.
TEST_F(StreamBoundsTest, PlanStreamClientThatNeverReadsIsReaped) {
  grpc::ClientContext context;
  SetDeadline(&context, std::chrono::seconds(60));
  auto stream = stub_->PlanStream(&context);
  const v1::PlanRequest big = RandomRequest(7, 8, v1::SOLVER_GEOMETRIC);
  auto writer = std::async(std::launch::async, [&] {
    int written = 0;
    while (written < 200'000 && stream->Write(big)) ++written;
    return written;
  });
  // Another stream is admitted once the first is reaped.
  const Clock::time_point start = Clock::now();
  bool admitted = false;
  while (!admitted && Clock::now() - start < std::chrono::seconds(20)) {
    std::this_thread::sleep_for(std::chrono::milliseconds(250));
    grpc::ClientContext second_context;
    SetDeadline(&second_context, std::chrono::seconds(10));
    auto second = stub_->PlanStream(&second_context);
    v1::PlanResponse response;
    admitted = second->Write(WrenchRequest()) && second->Read(&response);
    second->WritesDone();
    const grpc::Status s = second->Finish();
    if (!admitted) {
      EXPECT_EQ(s.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(s);
    }
  }
  EXPECT_TRUE(admitted) << "the stream that never reads still holds the only slot";
  context.TryCancel();
  const int written = writer.get();
  EXPECT_GT(written, 0);
}

TEST_F(StreamBoundsTest, FitInertiaBytesShareOneBudget) {
  // 2 MB budget: samples with 8 contacts hold ~330 bytes each plus the
  // vector's slack; 20,000 of them cannot fit.
  v1::FitInertiaRequest message;
  for (int i = 0; i < 2000; ++i) {
    v1::InertiaSample* s = message.add_samples();
    s->set_t(0.01 * i);
    s->mutable_orientation()->set_w(1.0);
    for (int c = 0; c < 8; ++c) {
      v1::ContactSample* contact = s->add_contacts();
      contact->mutable_point()->set_x(0.01 * c);
      contact->mutable_force()->set_z(1.0);
    }
  }
  std::vector<grpc::ByteBuffer> messages(10, Bytes(message));
  const grpc::Status status = StreamRaw(channel_, messages);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::RESOURCE_EXHAUSTED) << Describe(status);
  EXPECT_THAT(status.error_message(), HasSubstr("--max-inflight-bytes"));
  // Released: a small stream right after is served (or fails on its data,
  // never on the budget).
  const std::vector<v1::FitInertiaRequest> small = InertiaMessages(1, 200);
  const grpc::Status after = StreamRaw(channel_, {Bytes(small[0])});
  EXPECT_TRUE(after.ok()) << Describe(after);
}

// 1 MB of fit working memory: 300 samples fit with CONSTRAINED (~2 KB
// each) but not with FACTOR_GRAPH (~4.5 KB each), which is refused before
// it starts, naming the flag and the most samples it may have.
TEST_F(StreamBoundsTest, FitsBeyondTheWorkingMemoryLimitAreRefusedBeforeTheyStart) {
  std::vector<v1::FitInertiaRequest> messages = InertiaMessages(1, 300);
  messages[0].mutable_options()->set_method(v1::INERTIA_METHOD_CONSTRAINED);
  const grpc::Status constrained = StreamRaw(channel_, {Bytes(messages[0])});
  EXPECT_TRUE(constrained.ok()) << Describe(constrained);
  messages[0].mutable_options()->set_method(v1::INERTIA_METHOD_FACTOR_GRAPH);
  const grpc::Status factor_graph = StreamRaw(channel_, {Bytes(messages[0])});
  EXPECT_EQ(factor_graph.error_code(), grpc::StatusCode::INVALID_ARGUMENT)
      << Describe(factor_graph);
  EXPECT_THAT(factor_graph.error_message(), HasSubstr("--max-fit-bytes"));
  EXPECT_THAT(factor_graph.error_message(), HasSubstr("send at most 217 samples"));
}

class IpoptLaneTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override {
    return {"--workers", "1", "--ipopt-workers",    "1",
            "--queue",   "4", "--solve-timeout-ms", "120000"};
  }
};

// One worker: while a long Ipopt trajectory holds the Ipopt lane (a queued
// Ipopt plan misses its deadline), pooled geometric work (16 contacts,
// beyond the inline limit) is still served within a deadline far shorter
// than the trajectory: it has its own worker.
TEST_F(IpoptLaneTest, GeometricWorkIsServedWhileIpoptIsBusy) {
  v1::TrajectoryRequest slow = LiftRequest(2000);
  slow.mutable_plan()->set_solver(v1::SOLVER_IPOPT);
  grpc::ClientContext trajectory_context;
  SetDeadline(&trajectory_context, std::chrono::seconds(120));
  auto trajectory = std::async(std::launch::async, [&] {
    v1::TrajectoryResponse response;
    return stub_->PlanTrajectory(&trajectory_context, slow, &response);
  });
  grpc::Status queued;
  const Clock::time_point start = Clock::now();
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    v1::PlanResponse response;
    queued = CallPlan(*stub_, WrenchRequest(v1::SOLVER_IPOPT), &response,
                      std::chrono::milliseconds(300));
  } while (queued.ok() && Clock::now() - start < std::chrono::seconds(20));
  ASSERT_EQ(queued.error_code(), grpc::StatusCode::DEADLINE_EXCEEDED) << Describe(queued);
  // Geometric work on the pool, drawn per run, while Ipopt is still busy.
  std::mt19937_64 rng(::tactforce::testing::GtestSeed());
  for (int i = 0; i < 5; ++i) {
    v1::PlanResponse response;
    const grpc::Status s = CallPlan(*stub_, RandomRequest(rng(), 16, v1::SOLVER_GEOMETRIC),
                                    &response, std::chrono::seconds(2));
    EXPECT_TRUE(s.ok()) << Describe(s);
  }
  ASSERT_EQ(trajectory.wait_for(std::chrono::seconds(0)), std::future_status::timeout)
      << "the Ipopt trajectory ended too soon for this test to show anything";
  trajectory_context.TryCancel();
  const grpc::Status done = trajectory.get();
  EXPECT_EQ(done.error_code(), grpc::StatusCode::CANCELLED) << Describe(done);
}

}  // namespace
}  // namespace tactforce::testing
