// `tactforce load` against real tactforce-server processes (loopback only):
// the JSON report, each RPC kind and engine, open loop, and client-side
// round-robin over two replicas.
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "cli_test_support.h"

namespace tactforce::cli_testing {
namespace {

using ::testing::HasSubstr;

// Parses `load --json` output and checks the documented fields.
google::protobuf::Struct ParseReport(const ProcessResult& run) {
  absl::StatusOr<google::protobuf::Struct> json = ParseJsonObject(run.out);
  EXPECT_TRUE(json.ok()) << json.status() << "\n" << Describe(run);
  if (!json.ok()) return {};
  const auto& f = json->fields();
  for (const char* field :
       {"rpc", "concurrency", "requests", "duration_s", "qps", "latency_us", "errors"}) {
    EXPECT_TRUE(f.contains(field)) << field << " missing: " << run.out;
  }
  if (!f.contains("latency_us")) return *json;
  const auto& latency = f.at("latency_us").struct_value().fields();
  double previous = 0;
  for (const char* p : {"p50", "p90", "p99", "p999", "max"}) {
    EXPECT_TRUE(latency.contains(p)) << p << " missing: " << run.out;
    if (!latency.contains(p)) continue;
    const double value = latency.at(p).number_value();
    EXPECT_GE(value, previous) << p << " below the lower percentile: " << run.out;
    previous = value;
  }
  EXPECT_GT(latency.at("p50").number_value(), 0);
  return *json;
}

double Number(const google::protobuf::Struct& json, const std::string& field) {
  return json.fields().contains(field) ? json.fields().at(field).number_value() : -1;
}

int ErrorKinds(const google::protobuf::Struct& json) {
  return json.fields().contains("errors") ? json.fields().at("errors").struct_value().fields_size()
                                          : -1;
}

class LoadTest : public RemoteCliTest {};

TEST_F(LoadTest, PlanMixJsonHasNoErrors) {
  const ProcessResult run = Tactforce({"load", "--target", address(), "--rpc", "plan",
                                       "--requests", "2000", "--concurrency", "8", "--mix",
                                       "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  const google::protobuf::Struct json = ParseReport(run);
  EXPECT_EQ(json.fields().at("rpc").string_value(), "plan");
  EXPECT_EQ(Number(json, "concurrency"), 8);
  EXPECT_EQ(Number(json, "requests"), 2000);
  EXPECT_EQ(ErrorKinds(json), 0) << run.out;
  EXPECT_GT(Number(json, "qps"), 0);
  EXPECT_GT(Number(json, "duration_s"), 0);
}

TEST_F(LoadTest, StreamCallbackAndSync) {
  for (const char* engine : {"callback", "sync"}) {
    SCOPED_TRACE(engine);
    const ProcessResult run =
        Tactforce({"load", "--target", address(), "--rpc", "stream", "--requests", "1000",
                   "--concurrency", "4", "--engine", engine, "--json"});
    ASSERT_EQ(run.exit_code, 0) << Describe(run);
    const google::protobuf::Struct json = ParseReport(run);
    EXPECT_EQ(json.fields().at("rpc").string_value(), "stream");
    EXPECT_EQ(Number(json, "requests"), 1000);
    EXPECT_EQ(ErrorKinds(json), 0) << run.out;
  }
}

TEST_F(LoadTest, HealthAndSyncPlan) {
  ProcessResult run = Tactforce({"load", "--target", address(), "--rpc", "health", "--requests",
                                 "1000", "-c", "4", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  google::protobuf::Struct json = ParseReport(run);
  EXPECT_EQ(json.fields().at("rpc").string_value(), "health");
  EXPECT_EQ(Number(json, "requests"), 1000);

  run = Tactforce({"load", "--target", address(), "--rpc", "plan", "--engine", "sync",
                   "--requests", "500", "-c", "3", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  json = ParseReport(run);
  EXPECT_EQ(Number(json, "requests"), 500);
  EXPECT_EQ(ErrorKinds(json), 0) << run.out;
}

TEST_F(LoadTest, OpenLoopKeepsTheRate) {
  // 300 calls at 1000/s: ~0.3 s on schedule.
  const ProcessResult run = Tactforce({"load", "--target", address(), "--rate", "1000",
                                       "--requests", "300", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  const google::protobuf::Struct json = ParseReport(run);
  EXPECT_EQ(json.fields().at("mode").string_value(), "open");
  EXPECT_EQ(Number(json, "requests"), 300);
  EXPECT_GE(Number(json, "duration_s"), 0.29);
}

TEST_F(LoadTest, DurationBoundAndTextReport) {
  const ProcessResult run = Tactforce(
      {"load", "--target", address(), "--duration", "0.5", "-c", "2", "--progress"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_THAT(run.out, HasSubstr("throughput"));
  EXPECT_THAT(run.out, HasSubstr("p99.9"));
  EXPECT_THAT(run.out, HasSubstr("errors      none"));
  EXPECT_TRUE(run.err.empty()) << run.err;  // no progress line before 2 s
}

TEST_F(LoadTest, RequestFileAndItsErrors) {
  const std::string good = dir_.Write("pinch.json", ExampleRequestJson());
  ProcessResult run = Tactforce(
      {"load", "--target", address(), "--request", good, "--requests", "200", "--json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_EQ(Number(ParseReport(run), "requests"), 200);

  v1::PlanRequest request = RandomRequest(41, 3, v1::SOLVER_GEOMETRIC);
  request.mutable_contacts(2)->set_friction(-1);
  const std::string bad = dir_.Write("bad.json", RequestJson(request));
  run = Tactforce({"load", "--target", address(), "--request", bad, "--requests", "10"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("contacts[2].friction"));

  run = Tactforce({"load", "--target", address(), "--rpc", "stream", "--rate", "10",
                   "--requests", "10"});
  EXPECT_EQ(run.exit_code, 2) << Describe(run);
}

// ---------------------------------------------------------- two replicas

// Requests each replica logged (one "rpc=Plan " line per call at info).
int PlanLines(const ServerProcess& server) {
  const std::string log = server.StderrText();
  int lines = 0;
  for (size_t at = log.find("rpc=Plan "); at != std::string::npos;
       at = log.find("rpc=Plan ", at + 1)) {
    ++lines;
  }
  return lines;
}

TEST(LoadReplicasTest, TargetListSpreadsOverBothReplicas) {
  std::unique_ptr<ServerProcess> a = StartServer({"--log-level", "info"});
  std::unique_ptr<ServerProcess> b = StartServer({"--log-level", "info"});
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  // gRPC's round_robin policy over an ipv4: target, then one channel per
  // address with the client's own rotation.
  const std::vector<std::string> targets = {"ipv4:" + a->address() + "," + b->address(),
                                            a->address() + "," + b->address()};
  for (const std::string& target : targets) {
    SCOPED_TRACE(target);
    const int before_a = PlanLines(*a), before_b = PlanLines(*b);
    const ProcessResult run = Tactforce(
        {"load", "--target", target, "--requests", "1000", "-c", "4", "--json"});
    ASSERT_EQ(run.exit_code, 0) << Describe(run);
    EXPECT_EQ(Number(ParseReport(run), "requests"), 1000);
    // Logging is synchronous per call, so the lines are there.
    const int served_a = PlanLines(*a) - before_a, served_b = PlanLines(*b) - before_b;
    EXPECT_GE(served_a + served_b, 1000);
    EXPECT_GE(served_a, 250) << "replica a served " << served_a << ", b " << served_b;
    EXPECT_GE(served_b, 250) << "replica a served " << served_a << ", b " << served_b;
  }
  EXPECT_EQ(a->Stop(), 0);
  EXPECT_EQ(b->Stop(), 0);
}

}  // namespace
}  // namespace tactforce::cli_testing
