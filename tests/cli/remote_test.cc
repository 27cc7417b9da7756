// `tactforce plan`, `health` and `demo` against a real tactforce-server:
// remote answers equal local ones, errors are one line with the documented
// exit codes (cli_common.h: 2 invalid, 3 unavailable, 4 deadline exceeded).
#include <chrono>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_fixture.h"

namespace tactforce::cli_testing {
namespace {

using ::testing::HasSubstr;
using ::testing::Not;
using ::testing::StartsWith;

constexpr int kExitBadInput = 2;
constexpr int kExitUnavailable = 3;
constexpr int kExitDeadline = 4;

// Every error is exactly one line on stderr, starting "error: ".
void ExpectOneLineError(const ProcessResult& run) {
  EXPECT_THAT(run.err, StartsWith("error: ")) << Describe(run);
  ASSERT_FALSE(run.err.empty());
  EXPECT_EQ(run.err.find('\n'), run.err.size() - 1) << Describe(run);
}

void ExpectSameForces(const v1::PlanResponse& remote, const v1::PlanResponse& local) {
  EXPECT_EQ(remote.status(), local.status());
  ASSERT_EQ(remote.forces_size(), local.forces_size());
  for (int i = 0; i < remote.forces_size(); ++i) {
    EXPECT_NEAR(remote.forces(i).x(), local.forces(i).x(), 1e-12) << "contact " << i;
    EXPECT_NEAR(remote.forces(i).y(), local.forces(i).y(), 1e-12) << "contact " << i;
    EXPECT_NEAR(remote.forces(i).z(), local.forces(i).z(), 1e-12) << "contact " << i;
  }
  EXPECT_NEAR(remote.objective(), local.objective(), 1e-12);
}

class RemotePlanTest : public RemoteCliTest {};

TEST_F(RemotePlanTest, NetworkPlanEqualsLocalPlan) {
  std::vector<std::string> requests = {ExampleRequestJson()};
  for (uint64_t seed : {11, 12, 13, 14}) {
    requests.push_back(RequestJson(RandomRequest(seed, 3 + seed % 4, v1::SOLVER_GEOMETRIC)));
  }
  requests.push_back(RequestJson(RandomRequest(15, 4, v1::SOLVER_CROSS_CHECK)));
  int with_forces = 0;
  for (size_t i = 0; i < requests.size(); ++i) {
    SCOPED_TRACE("request " + std::to_string(i));
    const std::string path = dir_.Write("request" + std::to_string(i) + ".json", requests[i]);
    const ProcessResult remote =
        Tactforce({"plan", "--json", "--server", address(), "--request", path});
    const ProcessResult local = Tactforce({"plan", "--json", "--local", "--request", path});
    ASSERT_EQ(remote.exit_code, 0) << Describe(remote);
    ASSERT_EQ(local.exit_code, 0) << Describe(local);
    absl::StatusOr<v1::PlanResponse> r = ParsePlanResponse(remote.out);
    absl::StatusOr<v1::PlanResponse> l = ParsePlanResponse(local.out);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_TRUE(l.ok()) << l.status();
    if (r->forces_size() > 0) ++with_forces;  // random grasps may be infeasible
    ExpectSameForces(*r, *l);
    EXPECT_EQ(r->has_cross_check(), l->has_cross_check());
  }
  EXPECT_GE(with_forces, 3);
}

TEST_F(RemotePlanTest, TableFormatOverTheNetwork) {
  const std::string path = dir_.Write("pinch.json", ExampleRequestJson());
  const ProcessResult run =
      Tactforce({"plan", "--server", address(), "--request", path, "--format", "table"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_THAT(run.out, HasSubstr("OPTIMAL"));
  EXPECT_THAT(run.out, HasSubstr("thumb"));
}

TEST_F(RemotePlanTest, InvalidRequestIsExit2WithTheServersFieldPath) {
  v1::PlanRequest request = RandomRequest(21, 3, v1::SOLVER_GEOMETRIC);
  request.mutable_contacts(1)->mutable_normal()->Clear();  // zero length
  const std::string path = dir_.Write("bad.json", RequestJson(request));
  const ProcessResult run = Tactforce({"plan", "--json", "--server", address(), "--request", path});
  EXPECT_EQ(run.exit_code, kExitBadInput) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("contacts[1].normal"));
  ExpectOneLineError(run);
  EXPECT_TRUE(run.out.empty()) << run.out;
}

TEST_F(RemotePlanTest, DeadlineExceededIsExit4) {
  // 64 contacts with Ipopt: 25+ interior-point iterations on 192 variables and
  // ~900 rows take well over 20 ms; connecting to a loopback server does not.
  const std::string path =
      dir_.Write("slow.json", RequestJson(RandomRequest(31, 64, v1::SOLVER_IPOPT)));
  const ProcessResult run = Tactforce(
      {"plan", "--json", "--server", address(), "--request", path, "--deadline-ms", "20"});
  EXPECT_EQ(run.exit_code, kExitDeadline) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("no answer within 20 ms"));
  ExpectOneLineError(run);
}

TEST_F(RemotePlanTest, HealthIsServing) {
  ProcessResult run = Tactforce({"health", "--server", address()});
  EXPECT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_EQ(run.out, "SERVING\n");
  run = Tactforce({"health", "--server", address(), "--service", "tactforce.v1.Planner"});
  EXPECT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_EQ(run.out, "SERVING\n");
}

TEST_F(RemotePlanTest, HealthOfAnUnknownServiceIsExit2) {
  const ProcessResult run =
      Tactforce({"health", "--server", address(), "--service", "no.such.Service"});
  EXPECT_EQ(run.exit_code, kExitBadInput) << Describe(run);
  EXPECT_EQ(run.out, "SERVICE_UNKNOWN\n");
  ExpectOneLineError(run);
}

TEST_F(RemotePlanTest, DemoThroughTheServer) {
  const ProcessResult run =
      Tactforce({"demo", "--server", address(), "--repeat", "1", "--load-seconds", "1"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  EXPECT_THAT(run.out, HasSubstr("3 of 3 grasps agree"));  // the local table is kept
  EXPECT_THAT(run.out, HasSubstr("health: SERVING"));
  EXPECT_THAT(run.out, HasSubstr("3 of 3 server answers match the local ones"));
  EXPECT_THAT(run.out, HasSubstr("p99.9"));
  EXPECT_THAT(run.out, HasSubstr("errors      none"));
}

TEST_F(RemotePlanTest, DemoJsonThroughTheServer) {
  const ProcessResult run = Tactforce({"demo", "--server", address(), "--repeat", "1",
                                       "--load-seconds", "0.5", "--format", "json"});
  ASSERT_EQ(run.exit_code, 0) << Describe(run);
  absl::StatusOr<google::protobuf::Struct> json = ParseJsonObject(run.out);
  ASSERT_TRUE(json.ok()) << json.status() << "\n" << run.out;
  const auto& server = json->fields().at("server").struct_value();
  EXPECT_EQ(server.fields().at("health").string_value(), "SERVING");
  const auto& grasps = server.fields().at("grasps").list_value();
  ASSERT_EQ(grasps.values_size(), 3);
  for (const auto& grasp : grasps.values()) {
    EXPECT_TRUE(grasp.struct_value().fields().at("match").bool_value());
  }
  const auto& load = server.fields().at("load").struct_value();
  EXPECT_EQ(load.fields().at("errors").struct_value().fields_size(), 0);
  EXPECT_GT(load.fields().at("requests").number_value(), 0);
}

// ---------------------------------------------------------- no server

class UnreachableTest : public ::testing::Test {
 protected:
  std::string address_ = "127.0.0.1:" + std::to_string(ClosedPort());
  TempDir dir_;
};

TEST_F(UnreachableTest, PlanIsExit3Quickly) {
  const std::string path = dir_.Write("pinch.json", ExampleRequestJson());
  const auto start = std::chrono::steady_clock::now();
  const ProcessResult run = Tactforce(
      {"plan", "--json", "--server", address_, "--request", path, "--deadline-ms", "2000"});
  const auto elapsed = std::chrono::steady_clock::now() - start;
  EXPECT_EQ(run.exit_code, kExitUnavailable) << Describe(run);
  EXPECT_THAT(run.err, StartsWith("error: cannot reach " + address_ + ": "));
  ExpectOneLineError(run);
  EXPECT_LT(elapsed, std::chrono::seconds(5));
}

TEST_F(UnreachableTest, HealthAndLoadAreExit3) {
  ProcessResult run = Tactforce({"health", "--server", address_, "--deadline-ms", "2000"});
  EXPECT_EQ(run.exit_code, kExitUnavailable) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("cannot reach " + address_));
  EXPECT_TRUE(run.out.empty());
  ExpectOneLineError(run);

  run = Tactforce({"load", "--target", address_, "--requests", "10", "--deadline-ms", "1000"});
  EXPECT_EQ(run.exit_code, kExitUnavailable) << Describe(run);
  EXPECT_THAT(run.err, HasSubstr("cannot reach " + address_));
  ExpectOneLineError(run);
}

TEST_F(UnreachableTest, EveryCommandIsLocalByDefault) {
  // Without --local and --server a command computes in this process
  // (client/README.md, "Local or server: one convention"): no server is
  // asked, so none is needed.
  const std::string path = dir_.Write("pinch.json", ExampleRequestJson());
  const ProcessResult plan = Tactforce({"plan", "--json", "--request", path});
  ASSERT_EQ(plan.exit_code, 0) << Describe(plan);
  EXPECT_TRUE(ParsePlanResponse(plan.out).ok()) << plan.out;
  EXPECT_THAT(plan.err, Not(HasSubstr("localhost:50051")));
  const std::string example =
      (testing::SourceDir() / "client/examples/estimate_request.json").string();
  const ProcessResult estimate = Tactforce({"estimate", "--request", example});
  EXPECT_EQ(estimate.exit_code, 0) << Describe(estimate);
}

TEST_F(UnreachableTest, EveryRpcCommandTakesServer) {
  // The same --server flag in every command that makes an RPC: an
  // unreachable address is exit 3 naming it.
  const std::string examples = (testing::SourceDir() / "client/examples").string();
  ASSERT_EQ(
      Tactforce({"simulate", "friction", "--trials", "2", "--out", dir_.Path("fr")}).exit_code, 0);
  ASSERT_EQ(
      Tactforce({"simulate", "sensor", "--seconds", "5", "--out", dir_.Path("run")}).exit_code, 0);
  const std::vector<std::vector<std::string>> commands = {
      {"plan", "--request", examples + "/sphere_pinch.json"},
      {"estimate", "--request", examples + "/estimate_request.json"},
      {"friction", dir_.Path("fr/trial0.csv"), "--normal", "0,0,-1"},
      {"audit", "--csv", dir_.Path("run/run.csv"), "--out", dir_.Path("audit")},
      {"inertia", "--csv", examples + "/inertia_log.csv"},
  };
  for (std::vector<std::string> args : commands) {
    SCOPED_TRACE(args[0]);
    for (const char* a : {"--server", address_.c_str(), "--deadline-ms", "2000"}) args.push_back(a);
    const ProcessResult run = Tactforce(args);
    EXPECT_EQ(run.exit_code, kExitUnavailable) << Describe(run);
    EXPECT_THAT(run.err, StartsWith("error: cannot reach " + address_));
    ExpectOneLineError(run);
    args.push_back("--local");
    EXPECT_EQ(Tactforce(args).exit_code, kExitBadInput) << "--local excludes --server";
  }
}

TEST_F(UnreachableTest, BadConnectionFlagsAreExit2) {
  const std::string path = dir_.Write("pinch.json", ExampleRequestJson());
  ProcessResult run =
      Tactforce({"plan", "--json", "--local", "--server", address_, "--request", path});
  EXPECT_EQ(run.exit_code, kExitBadInput) << Describe(run);
  run = Tactforce({"plan", "--json", "--server", address_, "--request", path, "--tls-cert", path});
  EXPECT_EQ(run.exit_code, kExitBadInput) << Describe(run);  // needs --tls-key
  run = Tactforce({"plan", "--json", "--server", address_, "--request", path, "--tls-ca", path});
  EXPECT_EQ(run.exit_code, kExitBadInput) << Describe(run);  // not PEM
  EXPECT_THAT(run.err, HasSubstr("--tls-ca"));
}

// ------------------------------------------------------------------- TLS

// A CA, a server certificate for 127.0.0.1 and a client certificate, made
// with the openssl CLI in `dir`. Empty string on success, else the failure.
std::string MakeCertificates(const TempDir& dir) {
  const std::string d = dir.Path("");
  const std::string script =
      "set -e; cd '" + d +
      "'\n"
      "key() { openssl genpkey -algorithm EC -pkeyopt ec_paramgen_curve:P-256 -out $1.key; }\n"
      "key ca; key server; key client\n"
      "openssl req -x509 -new -key ca.key -days 1 -subj /CN=cli-test-ca -out ca.crt "
      "-addext basicConstraints=critical,CA:TRUE -addext keyUsage=critical,keyCertSign\n"
      "printf 'subjectAltName=IP:127.0.0.1\\nextendedKeyUsage=serverAuth\\n' > server.ext\n"
      "printf 'extendedKeyUsage=clientAuth\\n' > client.ext\n"
      "for leaf in server client; do\n"
      "  openssl req -new -key $leaf.key -subj /CN=cli-test-$leaf -out $leaf.csr\n"
      "  openssl x509 -req -in $leaf.csr -CA ca.crt -CAkey ca.key -CAcreateserial -days 1 "
      "-extfile $leaf.ext -out $leaf.crt\n"
      "done\n";
  const ProcessResult run = testing::RunProcess({"/bin/sh", "-c", script});
  return run.exit_code == 0 ? "" : Describe(run);
}

TEST(RemoteTlsTest, MutualTls) {
  TempDir dir;
  const std::string failure = MakeCertificates(dir);
  ASSERT_EQ(failure, "") << failure;
  std::unique_ptr<ServerProcess> server =
      StartServer({"--tls-cert", dir.Path("server.crt"), "--tls-key", dir.Path("server.key"),
                   "--tls-client-ca", dir.Path("ca.crt")});
  ASSERT_NE(server, nullptr);
  const std::vector<std::string> tls = {"--tls-ca",   dir.Path("ca.crt"),
                                        "--tls-cert", dir.Path("client.crt"),
                                        "--tls-key",  dir.Path("client.key")};
  auto with_tls = [&](std::vector<std::string> args) {
    args.insert(args.end(), tls.begin(), tls.end());
    return args;
  };
  const std::string request = dir.Write("pinch.json", ExampleRequestJson());

  ProcessResult run = Tactforce(with_tls({"health", "--server", server->address()}));
  EXPECT_EQ(run.exit_code, 0) << Describe(run);
  run =
      Tactforce(with_tls({"plan", "--json", "--server", server->address(), "--request", request}));
  EXPECT_EQ(run.exit_code, 0) << Describe(run);
  run = Tactforce(
      with_tls({"load", "--target", server->address(), "--requests", "200", "-c", "2", "--json"}));
  EXPECT_EQ(run.exit_code, 0) << Describe(run);

  // Server-authenticated TLS only: the server wants a client certificate.
  run = Tactforce({"health", "--server", server->address(), "--tls-ca", dir.Path("ca.crt"),
                   "--deadline-ms", "2000"});
  EXPECT_EQ(run.exit_code, kExitUnavailable) << Describe(run);
  // Plaintext against a TLS server.
  run = Tactforce({"health", "--server", server->address(), "--deadline-ms", "2000"});
  EXPECT_EQ(run.exit_code, kExitUnavailable) << Describe(run);
  EXPECT_EQ(server->Stop(), 0);
}

class BackendConventionTest : public RemoteCliTest {};

// friction and audit, which had no --server before, give the server's
// answer as they give the local one.
TEST_F(BackendConventionTest, FrictionAndAuditOnTheServerEqualLocal) {
  ASSERT_EQ(
      Tactforce({"simulate", "friction", "--trials", "3", "--seed", "4", "--out", dir_.Path("fr")})
          .exit_code,
      0);
  const std::vector<std::string> friction = {"friction",
                                             dir_.Path("fr/trial0.csv"),
                                             dir_.Path("fr/trial1.csv"),
                                             dir_.Path("fr/trial2.csv"),
                                             "--normal",
                                             "0,0,-1"};
  const ProcessResult local = Tactforce(friction);
  std::vector<std::string> remote_args = friction;
  remote_args.insert(remote_args.end(), {"--server", address()});
  const ProcessResult remote = Tactforce(remote_args);
  ASSERT_EQ(local.exit_code, 0) << Describe(local);
  ASSERT_EQ(remote.exit_code, 0) << Describe(remote);
  EXPECT_EQ(local.out, remote.out);

  ASSERT_EQ(Tactforce({"simulate", "sensor", "--model",
                       (testing::SourceDir() / "client/examples/sensor_model.json").string(),
                       "--seconds", "10", "--out", dir_.Path("run")})
                .exit_code,
            0);
  const std::vector<std::string> audit = {
      "audit", "--csv", dir_.Path("run/run.csv"), "--max-causes", "1", "--blocks", "0"};
  std::vector<std::string> audit_local = audit, audit_remote = audit;
  audit_local.insert(audit_local.end(), {"--out", dir_.Path("local")});
  audit_remote.insert(audit_remote.end(), {"--out", dir_.Path("remote"), "--server", address()});
  const ProcessResult a = Tactforce(audit_local, std::chrono::seconds(120));
  const ProcessResult b = Tactforce(audit_remote, std::chrono::seconds(120));
  ASSERT_EQ(a.exit_code, 0) << Describe(a);
  ASSERT_EQ(b.exit_code, 0) << Describe(b);
  EXPECT_EQ(a.out, b.out);  // the summary
  for (const char* file : {"report.json", "summary.txt", "extended_model.json"}) {
    EXPECT_TRUE(std::filesystem::exists(dir_.Path("remote") + "/" + file)) << file;
  }
  // Two streams carry a clock offset AuditRequest cannot: refused, naming --server.
  const std::string examples = (testing::SourceDir() / "client/examples").string();
  const ProcessResult streams =
      Tactforce({"audit", "--reference", examples + "/reference.csv", "--reading",
                 examples + "/reading.csv", "--out", dir_.Path("streams"), "--server", address()});
  EXPECT_EQ(streams.exit_code, kExitBadInput) << Describe(streams);
  EXPECT_THAT(streams.err, HasSubstr("--server"));
  ExpectOneLineError(streams);
}

class RemoteInertiaTest : public RemoteCliTest {};

// `tactforce inertia --server` streams the CSV to Estimator.FitInertia in
// batches and prints the same answer as the local fit.
TEST_F(RemoteInertiaTest, StreamedFitEqualsLocalFit) {
  const std::string sim = dir_.Path("sim");
  ASSERT_EQ(
      Tactforce({"simulate", "inertia", "--out", sim, "--seconds", "3", "--force-variance", "0.25"})
          .exit_code,
      0);
  const std::vector<std::string> fit = {
      "inertia",           "--csv",  sim + "/inertia.csv", "--truth",
      sim + "/truth.json", "--json", "--method",           "factor-graph"};
  const ProcessResult local = Tactforce(fit);
  ASSERT_EQ(local.exit_code, 0) << Describe(local);
  std::vector<std::string> remote_args = fit;
  for (const char* a : {"--server", "", "--batch", "37"}) remote_args.push_back(a);
  remote_args[remote_args.size() - 3] = address();
  const ProcessResult remote = Tactforce(remote_args);
  ASSERT_EQ(remote.exit_code, 0) << Describe(remote);
  absl::StatusOr<google::protobuf::Struct> a = ParseJsonObject(local.out);
  absl::StatusOr<google::protobuf::Struct> b = ParseJsonObject(remote.out);
  ASSERT_TRUE(a.ok() && b.ok());
  for (const char* key : {"mass", "physically_consistent", "samples_received"}) {
    ASSERT_TRUE(a->fields().contains(key)) << key;
    EXPECT_EQ(a->fields().at(key).DebugString(), b->fields().at(key).DebugString()) << key;
  }
  EXPECT_EQ(a->fields().at("inertia").DebugString(), b->fields().at("inertia").DebugString());
  // A bad file is rejected before anything is sent.
  const std::string bad = dir_.Write("bad.csv", "t,px\n0,0\n");
  const ProcessResult r = Tactforce({"inertia", "--csv", bad, "--server", address()});
  EXPECT_EQ(r.exit_code, kExitBadInput) << Describe(r);
  ExpectOneLineError(r);
}

}  // namespace
}  // namespace tactforce::cli_testing
