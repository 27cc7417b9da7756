// tactforce.v1.Planner/PlanStream: one response per request, in order;
// invalid requests end the stream; client cancellation stops the work.
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_support.h"

namespace tactforce::testing {
namespace {

using ::testing::HasSubstr;
using ::testing::StartsWith;

int CountOccurrences(const std::string& text, const std::string& needle) {
  int n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

class StreamTest : public ServerTest {
 protected:
  std::vector<std::string> server_flags() const override { return {"--log-level", "info"}; }
};

TEST_F(StreamTest, ResponsesComeInRequestOrder) {
  // A mix that runs inline (small geometric) and on the pool (Ipopt,
  // larger geometric), so completion order would differ from request order
  // if the server did not keep it.
  std::vector<v1::PlanRequest> requests;
  for (int i = 0; i < 36; ++i) {
    const v1::Solver solver = i % 3 == 1 ? v1::SOLVER_IPOPT : v1::SOLVER_GEOMETRIC;
    const int contacts = i % 3 == 2 ? 14 : 2 + i % 5;
    requests.push_back(RandomRequest(1000 + i, contacts, solver, /*allow_infeasible=*/true));
  }
  // Expected answers, one unary call each.
  std::vector<v1::PlanResponse> expected(requests.size());
  for (size_t i = 0; i < requests.size(); ++i) {
    grpc::Status status = CallPlan(*stub_, requests[i], &expected[i]);
    ASSERT_TRUE(status.ok()) << i << ": " << Describe(status);
  }

  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(60));
  auto stream = stub_->PlanStream(&context);
  std::thread writer([&] {
    for (const v1::PlanRequest& r : requests) {
      if (!stream->Write(r)) break;
    }
    stream->WritesDone();
  });
  std::vector<v1::PlanResponse> responses;
  for (v1::PlanResponse r; stream->Read(&r);) responses.push_back(r);
  writer.join();
  grpc::Status status = stream->Finish();
  ASSERT_TRUE(status.ok()) << Describe(status);

  ASSERT_EQ(responses.size(), requests.size());
  EXPECT_TRUE(server_->WaitForStderr("rpc=PlanStream event=end code=OK responses=36 ",
                                     std::chrono::seconds(5)));
  for (size_t i = 0; i < responses.size(); ++i) {
    SCOPED_TRACE("response " + std::to_string(i));
    EXPECT_EQ(responses[i].status(), expected[i].status());
    EXPECT_EQ(responses[i].solver(), requests[i].solver());
    ASSERT_EQ(responses[i].forces_size(), expected[i].forces_size());
    ASSERT_EQ(responses[i].forces_size() == 0, expected[i].status() != v1::PLAN_STATUS_OPTIMAL);
    for (int k = 0; k < responses[i].forces_size(); ++k) {
      EXPECT_NEAR(responses[i].forces(k).x(), expected[i].forces(k).x(), 1e-9);
      EXPECT_NEAR(responses[i].forces(k).y(), expected[i].forces(k).y(), 1e-9);
      EXPECT_NEAR(responses[i].forces(k).z(), expected[i].forces(k).z(), 1e-9);
    }
  }
}

TEST_F(StreamTest, InvalidRequestEndsTheStreamNamingRequestAndField) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
  auto stream = stub_->PlanStream(&context);
  v1::PlanRequest bad = WrenchRequest();
  bad.mutable_contacts(1)->mutable_normal()->Clear();
  ASSERT_TRUE(stream->Write(WrenchRequest()));
  ASSERT_TRUE(stream->Write(WrenchRequest(v1::SOLVER_IPOPT)));
  stream->Write(bad);
  stream->WritesDone();
  std::vector<v1::PlanResponse> responses;
  for (v1::PlanResponse r; stream->Read(&r);) responses.push_back(r);
  grpc::Status status = stream->Finish();
  EXPECT_EQ(responses.size(), 2u);
  EXPECT_EQ(status.error_code(), grpc::StatusCode::INVALID_ARGUMENT) << Describe(status);
  EXPECT_EQ(status.error_message(), "request 2: contacts[1].normal: zero length");
}

TEST_F(StreamTest, EmptyStreamIsOk) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(10));
  auto stream = stub_->PlanStream(&context);
  stream->WritesDone();
  v1::PlanResponse r;
  EXPECT_FALSE(stream->Read(&r));
  grpc::Status status = stream->Finish();
  EXPECT_TRUE(status.ok()) << Describe(status);
}

TEST_F(StreamTest, ClientCancellationStopsTheWork) {
  // 100 Ipopt requests (~20-100 ms each) queued on the stream; the client
  // reads two answers and cancels. The server must stop instead of
  // working through the rest.
  constexpr int kRequests = 100;
  grpc::ClientContext context;
  auto stream = stub_->PlanStream(&context);
  std::thread writer([&] {
    for (int i = 0; i < kRequests; ++i) {
      if (!stream->Write(RandomRequest(2000 + i, 4 + i % 3, v1::SOLVER_IPOPT))) break;
    }
  });
  v1::PlanResponse response;
  ASSERT_TRUE(stream->Read(&response));
  ASSERT_TRUE(stream->Read(&response));
  context.TryCancel();
  writer.join();
  while (stream->Read(&response)) {
  }
  grpc::Status status = stream->Finish();
  EXPECT_EQ(status.error_code(), grpc::StatusCode::CANCELLED) << Describe(status);

  // The server ends the stream as cancelled, having solved only the few
  // requests before the cancellation (plus at most the one in progress).
  ASSERT_TRUE(
      server_->WaitForStderr("rpc=PlanStream event=end code=CANCELLED", std::chrono::seconds(10)))
      << server_->StderrText().substr(0, 3000);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const std::string log = server_->StderrText();
  EXPECT_LE(CountOccurrences(log, "rpc=PlanStream index="), 5) << log.substr(0, 3000);

  // ... and keeps serving.
  grpc::Status ok = CallPlan(*stub_, WrenchRequest(), &response);
  EXPECT_TRUE(ok.ok()) << Describe(ok);
}

TEST_F(StreamTest, CancellingDuringASlowSolve) {
  grpc::ClientContext context;
  auto stream = stub_->PlanStream(&context);
  ASSERT_TRUE(stream->Write(WrenchRequest()));
  v1::PlanResponse response;
  ASSERT_TRUE(stream->Read(&response));
  ASSERT_TRUE(stream->Write(SlowIpoptRequest()));
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  context.TryCancel();
  EXPECT_FALSE(stream->Read(&response));
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::CANCELLED);
  EXPECT_TRUE(
      server_->WaitForStderr("rpc=PlanStream index=1 code=CANCELLED", std::chrono::seconds(10)))
      << server_->StderrText();
}

TEST_F(StreamTest, StreamDeadline) {
  grpc::ClientContext context;
  context.set_deadline(std::chrono::system_clock::now() + std::chrono::milliseconds(50));
  auto stream = stub_->PlanStream(&context);
  stream->Write(SlowIpoptRequest());
  v1::PlanResponse response;
  EXPECT_FALSE(stream->Read(&response));
  EXPECT_EQ(stream->Finish().error_code(), grpc::StatusCode::DEADLINE_EXCEEDED);
  // The stream's end line always carries the code. The request's own line
  // exists only if the server read the request before the deadline, which a
  // loaded machine (ctest -j2 beside the heavy tests) can miss at 50 ms.
  EXPECT_TRUE(server_->WaitForStderr("rpc=PlanStream event=end code=DEADLINE_EXCEEDED",
                                     std::chrono::seconds(10)))
      << server_->StderrText();
  const std::string log = server_->StderrText();
  if (log.find("rpc=PlanStream index=0 ") != std::string::npos)
    EXPECT_NE(log.find("rpc=PlanStream index=0 code=DEADLINE_EXCEEDED"), std::string::npos) << log;
}

}  // namespace
}  // namespace tactforce::testing
