// The tactforce-server process: flags, startup errors, signals and the
// graceful drain.
#include <signal.h>

#include <atomic>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "grpc/health/v1/health.grpc.pb.h"
#include "test_support.h"

namespace tactforce::testing {
namespace {

using ::testing::HasSubstr;
using Clock = std::chrono::steady_clock;

std::string Server() { return BinaryPath("tactforce-server").string(); }

int CountOccurrences(const std::string& text, const std::string& needle) {
  int n = 0;
  for (size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + 1)) ++n;
  return n;
}

TEST(ServerCliTest, HelpDocumentsEveryFlag) {
  ProcessResult run = RunProcess({Server(), "--help"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* flag :
       {"--listen", "--workers", "--queue", "--max-message-bytes", "--max-contacts",
        "--solve-timeout-ms", "--inline-max-contacts", "--tls-cert", "--tls-key", "--tls-client-ca",
        "--log-level", "--grace-ms", "--version"}) {
    EXPECT_THAT(run.out, HasSubstr(flag));
  }
  // Loopback unless asked otherwise; documented defaults.
  EXPECT_THAT(run.out, HasSubstr("127.0.0.1:50051"));
  EXPECT_THAT(run.out, HasSubstr("4194304"));
  EXPECT_THAT(run.out, HasSubstr("0.0.0.0:50051"));
}

TEST(ServerCliTest, BadFlagsAreRejected) {
  for (const std::vector<std::string>& args : std::vector<std::vector<std::string>>{
           {"--workers", "-1"},
           {"--queue", "x"},
           {"--log-level", "loud"},
           {"--max-contacts", "0"},
           {"--tls-cert", "/nonexistent/cert.pem", "--tls-key", "/nonexistent/key.pem"},
           {"--tls-key", "/etc/hostname"},  // needs --tls-cert
           {"--no-such-flag"},
           {"--listen", "127.0.0.1:99999"},
           {"--listen", "127.0.0.1:http"},
           {"--listen", "127.0.0.1"}}) {
    std::vector<std::string> argv = {Server()};
    argv.insert(argv.end(), args.begin(), args.end());
    ProcessResult run = RunProcess(argv);
    EXPECT_EQ(run.exit_code, 2) << args[0] << " " << args.back();
    EXPECT_FALSE(run.err.empty()) << args[0];
    EXPECT_TRUE(run.out.empty()) << args[0] << ": " << run.out;
  }
}

TEST(ServerCliTest, StartupErrorsExitOne) {
  // Not PEM.
  ProcessResult run = RunProcess({Server(), "--listen", "127.0.0.1:0", "--tls-cert",
                                  "/etc/hostname", "--tls-key", "/etc/hostname"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.err, HasSubstr("--tls-cert: /etc/hostname is not PEM"));
  // Not an address this machine has.
  run = RunProcess({Server(), "--listen", "192.0.2.1:0"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.err, HasSubstr("cannot listen on 192.0.2.1:0"));
}

// gRPC turns SO_REUSEPORT on by default: a second server on a port in use
// would start and silently take half of the calls. It must fail instead,
// unless both ask for --reuse-port.
TEST(ServerCliTest, SecondServerOnAPortInUseExitsOne) {
  std::string error;
  auto first = ServerProcess::Start({}, &error);
  ASSERT_NE(first, nullptr) << error;
  ProcessResult run =
      RunProcess({Server(), "--listen", first->address()}, {}, std::chrono::seconds(10));
  EXPECT_EQ(run.exit_code, 1) << run.out;
  EXPECT_THAT(run.err, HasSubstr("cannot listen on " + first->address()));
  EXPECT_TRUE(run.out.empty()) << run.out;

  // --reuse-port on the second alone is not enough: the first did not share.
  run = RunProcess({Server(), "--listen", first->address(), "--reuse-port"}, {},
                   std::chrono::seconds(10));
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_THAT(run.err, HasSubstr("cannot listen on " + first->address()));

  // Both asking: the second starts and listens (stopped by the timeout).
  auto sharing = ServerProcess::Start({"--reuse-port"}, &error);
  ASSERT_NE(sharing, nullptr) << error;
  run = RunProcess({Server(), "--listen", sharing->address(), "--reuse-port"}, {},
                   std::chrono::seconds(2));
  EXPECT_THAT(run.out, HasSubstr("listening on " + sharing->address()));
  EXPECT_EQ(sharing->Stop(), 0);
  EXPECT_EQ(first->Stop(), 0);
}

TEST(ServerLifecycleTest, SigintAlsoStopsCleanly) {
  std::string error;
  auto server = ServerProcess::Start({}, &error);
  ASSERT_NE(server, nullptr) << error;
  server->Signal(SIGINT);
  EXPECT_EQ(server->WaitExit(std::chrono::seconds(10)).value_or(-1), 0);
}

// New connections are refused while draining.
void ExpectNewConnectionsRefused(const std::string& address) {
  auto fresh = Connect(address, grpc::InsecureChannelCredentials(), [] {
    grpc::ChannelArguments args;
    args.SetInt(GRPC_ARG_USE_LOCAL_SUBCHANNEL_POOL, 1);
    return args;
  }());
  auto fresh_stub = v1::Planner::NewStub(fresh);
  v1::PlanResponse ignored;
  grpc::Status status =
      CallPlan(*fresh_stub, WrenchRequest(), &ignored, std::chrono::milliseconds(2000));
  EXPECT_FALSE(status.ok());
}

// Unary solves really were in flight at the signal: some finished after it.
void ExpectSolvesFinishedAfterTheShutdown(const std::string& log) {
  const size_t shutdown_at = log.find("event=shutdown");
  ASSERT_NE(shutdown_at, std::string::npos) << log;
  EXPECT_NE(log.find("rpc=Plan code=OK solver=IPOPT contacts=60", shutdown_at), std::string::npos)
      << log;
  EXPECT_NE(log.find("event=drained", shutdown_at), std::string::npos) << log;
}

TEST(ServerLifecycleTest, SigtermDrainsInFlightCallsAndExitsZero) {
  std::string error;
  auto server = ServerProcess::Start(
      {"--workers", "1", "--grace-ms", "20000", "--log-level", "debug"}, &error);
  ASSERT_NE(server, nullptr) << error;
  auto channel = Connect(server->address());
  auto stub = v1::Planner::NewStub(channel);

  // A health watcher, to see the switch to NOT_SERVING.
  auto health = grpc::health::v1::Health::NewStub(channel);
  grpc::ClientContext watch_context;
  grpc::health::v1::HealthCheckRequest watch_request;
  auto watch = health->Watch(&watch_context, watch_request);
  grpc::health::v1::HealthCheckResponse health_status;
  ASSERT_TRUE(watch->Read(&health_status));
  EXPECT_EQ(health_status.status(), grpc::health::v1::HealthCheckResponse::SERVING);

  // An open stream that has already answered once.
  grpc::ClientContext stream_context;
  auto stream = stub->PlanStream(&stream_context);
  v1::PlanResponse response;
  ASSERT_TRUE(stream->Write(WrenchRequest()));
  ASSERT_TRUE(stream->Read(&response));

  // Three slow unary solves: one running on the only worker, two queued.
  constexpr int kUnary = 3;
  std::vector<grpc::Status> statuses(kUnary);
  std::vector<v1::PlanResponse> answers(kUnary);
  std::vector<std::thread> calls;
  for (int i = 0; i < kUnary; ++i) {
    calls.emplace_back([&, i] {
      grpc::ClientContext context;
      context.set_deadline(std::chrono::system_clock::now() + std::chrono::seconds(30));
      statuses[i] = stub->Plan(&context, SlowIpoptRequest(100 + i), &answers[i]);
    });
  }
  const auto queued_deadline = Clock::now() + std::chrono::seconds(10);
  while (CountOccurrences(server->StderrText(), "rpc=Plan event=queued") < kUnary &&
         Clock::now() < queued_deadline) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(CountOccurrences(server->StderrText(), "rpc=Plan event=queued"), kUnary);
  ASSERT_TRUE(stream->Write(WrenchRequest(v1::SOLVER_IPOPT)));

  const auto signalled = Clock::now();
  server->Signal(SIGTERM);

  // Health goes NOT_SERVING.
  ASSERT_TRUE(watch->Read(&health_status));
  EXPECT_EQ(health_status.status(), grpc::health::v1::HealthCheckResponse::NOT_SERVING);
  watch_context.TryCancel();
  while (watch->Read(&health_status)) {
  }
  (void)watch->Finish();

  ExpectNewConnectionsRefused(server->address());

  // Every in-flight call completes normally.
  for (std::thread& t : calls) t.join();
  for (int i = 0; i < kUnary; ++i) {
    EXPECT_TRUE(statuses[i].ok()) << i << ": " << Describe(statuses[i]);
    EXPECT_EQ(answers[i].status(), v1::PLAN_STATUS_OPTIMAL) << answers[i].message();
  }
  ASSERT_TRUE(stream->Read(&response));
  EXPECT_EQ(response.solver(), v1::SOLVER_IPOPT);
  EXPECT_EQ(response.status(), v1::PLAN_STATUS_OPTIMAL);
  stream->WritesDone();
  EXPECT_FALSE(stream->Read(&response));
  grpc::Status stream_status = stream->Finish();
  EXPECT_TRUE(stream_status.ok()) << Describe(stream_status);

  EXPECT_EQ(server->WaitExit(std::chrono::seconds(20)).value_or(-1), 0) << server->StderrText();
  EXPECT_LT(Clock::now() - signalled, std::chrono::seconds(15));
  ExpectSolvesFinishedAfterTheShutdown(server->StderrText());
}

TEST(ServerLifecycleTest, GracePeriodBoundsTheDrain) {
  std::string error;
  auto server = ServerProcess::Start({"--grace-ms", "300"}, &error);
  ASSERT_NE(server, nullptr) << error;
  auto stub = v1::Planner::NewStub(Connect(server->address()));
  // A stream the client never closes.
  grpc::ClientContext context;
  auto stream = stub->PlanStream(&context);
  v1::PlanResponse response;
  ASSERT_TRUE(stream->Write(WrenchRequest()));
  ASSERT_TRUE(stream->Read(&response));

  const auto signalled = Clock::now();
  server->Signal(SIGTERM);
  EXPECT_EQ(server->WaitExit(std::chrono::seconds(10)).value_or(-1), 0) << server->StderrText();
  EXPECT_LT(Clock::now() - signalled, std::chrono::seconds(3));
  EXPECT_FALSE(stream->Read(&response));
  EXPECT_FALSE(stream->Finish().ok());
}

TEST(ServerLifecycleTest, SecondSignalExitsAtOnce) {
  std::string error;
  auto server = ServerProcess::Start({"--grace-ms", "60000"}, &error);
  ASSERT_NE(server, nullptr) << error;
  auto stub = v1::Planner::NewStub(Connect(server->address()));
  grpc::ClientContext context;
  auto stream = stub->PlanStream(&context);
  v1::PlanResponse response;
  ASSERT_TRUE(stream->Write(WrenchRequest()));
  ASSERT_TRUE(stream->Read(&response));
  server->Signal(SIGTERM);
  // Still draining (the stream is open) ...
  EXPECT_FALSE(server->WaitExit(std::chrono::milliseconds(300)).has_value());
  server->Signal(SIGTERM);
  EXPECT_EQ(server->WaitExit(std::chrono::seconds(10)).value_or(-1), 128 + SIGTERM);
  context.TryCancel();
}

}  // namespace
}  // namespace tactforce::testing
