// CallUnary and RemoteServer (client/remote_call.h) against an in-process
// fake Planner: the answer comes back, and every way a call fails becomes the
// error the CLI prints (the server's field path, "ADDR: message", the
// deadline, an unreachable server, an unreadable TLS file).
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <grpcpp/grpcpp.h>

#include "remote_call.h"
#include "tactforce/v1/planner.grpc.pb.h"

namespace tactforce::cli {
namespace {

using ::testing::StartsWith;

// Answers Plan by the request: no contacts -> INVALID_ARGUMENT naming the
// field; SOLVER_IPOPT -> RESOURCE_EXHAUSTED; SOLVER_CROSS_CHECK -> answers
// after 500 ms; otherwise objective = number of contacts.
class FakePlanner final : public v1::Planner::Service {
 public:
  grpc::Status Plan(grpc::ServerContext*, const v1::PlanRequest* request,
                    v1::PlanResponse* response) override {
    if (request->contacts_size() == 0) {
      return grpc::Status(grpc::StatusCode::INVALID_ARGUMENT, "contacts: at least one needed");
    }
    if (request->solver() == v1::SOLVER_IPOPT) {
      return grpc::Status(grpc::StatusCode::RESOURCE_EXHAUSTED, "worker pool full");
    }
    if (request->solver() == v1::SOLVER_CROSS_CHECK) {
      std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
    response->set_objective(request->contacts_size());
    return grpc::Status::OK;
  }
};

class RemoteCallTest : public ::testing::Test {
 protected:
  void SetUp() override {
    grpc::ServerBuilder builder;
    builder.AddListeningPort("127.0.0.1:0", grpc::InsecureServerCredentials(), &port_);
    builder.RegisterService(&planner_);
    server_ = builder.BuildAndStart();
    ASSERT_NE(server_, nullptr);
    ASSERT_GT(port_, 0);
    address_ = "127.0.0.1:" + std::to_string(port_);
  }
  void TearDown() override {
    if (server_ != nullptr) server_->Shutdown(std::chrono::system_clock::now());
  }

  ConnectionArgs Args(int deadline_ms) const {
    ConnectionArgs args;
    args.server = address_;
    args.deadline_ms = deadline_ms;
    return args;
  }

  static v1::PlanRequest Request(int contacts, v1::Solver solver) {
    v1::PlanRequest request;
    for (int i = 0; i < contacts; ++i) request.add_contacts();
    request.set_solver(solver);
    return request;
  }

  FakePlanner planner_;
  std::unique_ptr<grpc::Server> server_;
  int port_ = 0;
  std::string address_;
};

TEST_F(RemoteCallTest, AnswersComeBackThroughEveryOverload) {
  absl::StatusOr<RemoteServer> server = RemoteServer::Open(Args(5'000));
  ASSERT_TRUE(server.ok()) << server.status();
  EXPECT_EQ(server->target(), address_);
  EXPECT_EQ(server->deadline_ms(), 5'000);

  v1::Planner::Stub stub(server->channel());
  absl::StatusOr<v1::PlanResponse> kept =
      CallUnary(*server, stub, &v1::Planner::Stub::Plan, Request(3, v1::SOLVER_GEOMETRIC));
  ASSERT_TRUE(kept.ok()) << kept.status();
  EXPECT_EQ(kept->objective(), 3);

  absl::StatusOr<v1::PlanResponse> fresh =
      CallUnary(*server, &v1::Planner::Stub::Plan, Request(2, v1::SOLVER_GEOMETRIC));
  ASSERT_TRUE(fresh.ok()) << fresh.status();
  EXPECT_EQ(fresh->objective(), 2);

  absl::StatusOr<v1::PlanResponse> one_off =
      CallUnary(Args(5'000), &v1::Planner::Stub::Plan, Request(4, v1::SOLVER_GEOMETRIC));
  ASSERT_TRUE(one_off.ok()) << one_off.status();
  EXPECT_EQ(one_off->objective(), 4);
}

TEST_F(RemoteCallTest, ServerErrorsBecomeTheCliErrors) {
  absl::StatusOr<v1::PlanResponse> invalid =
      CallUnary(Args(5'000), &v1::Planner::Stub::Plan, Request(0, v1::SOLVER_GEOMETRIC));
  EXPECT_EQ(invalid.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(invalid.status().message(), "contacts: at least one needed");

  absl::StatusOr<v1::PlanResponse> busy =
      CallUnary(Args(5'000), &v1::Planner::Stub::Plan, Request(1, v1::SOLVER_IPOPT));
  EXPECT_EQ(busy.status().code(), absl::StatusCode::kResourceExhausted);
  EXPECT_EQ(busy.status().message(), address_ + ": worker pool full");
}

TEST_F(RemoteCallTest, SlowAnswerIsDeadlineExceededNamingTheFlag) {
  absl::StatusOr<RemoteServer> server = RemoteServer::Open(Args(100));
  ASSERT_TRUE(server.ok()) << server.status();
  // Connect first, so that the deadline is about the answer, not the connection.
  ASSERT_TRUE(CallUnary(*server, &v1::Planner::Stub::Plan, Request(1, v1::SOLVER_GEOMETRIC)).ok());
  absl::StatusOr<v1::PlanResponse> slow =
      CallUnary(*server, &v1::Planner::Stub::Plan, Request(1, v1::SOLVER_CROSS_CHECK));
  EXPECT_EQ(slow.status().code(), absl::StatusCode::kDeadlineExceeded);
  EXPECT_EQ(slow.status().message(), address_ + ": no answer within 100 ms (--deadline-ms)");
}

TEST_F(RemoteCallTest, StoppedServerIsUnavailable) {
  server_->Shutdown(std::chrono::system_clock::now());
  server_->Wait();
  server_.reset();
  absl::StatusOr<v1::PlanResponse> response =
      CallUnary(Args(5'000), &v1::Planner::Stub::Plan, Request(1, v1::SOLVER_GEOMETRIC));
  EXPECT_EQ(response.status().code(), absl::StatusCode::kUnavailable);
  EXPECT_THAT(std::string(response.status().message()),
              StartsWith("cannot reach " + address_ + ": "));
}

TEST_F(RemoteCallTest, UnreadableTlsFileFailsBeforeAnyCall) {
  ConnectionArgs args = Args(5'000);
  args.tls_ca = "/nonexistent/ca.pem";
  absl::StatusOr<v1::PlanResponse> response =
      CallUnary(args, &v1::Planner::Stub::Plan, Request(1, v1::SOLVER_GEOMETRIC));
  EXPECT_EQ(response.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(response.status().message()),
              StartsWith("--tls-ca: cannot read '/nonexistent/ca.pem'"));
}

}  // namespace
}  // namespace tactforce::cli
