// The CLI test harness (cli_fixture.h): the binary run through RunProcess,
// file helpers, the bad-input checks, JSON and request helpers, and the
// per-suite tactforce-server.
#include "support/cli_fixture.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include <google/protobuf/util/json_util.h>

#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::testing {
namespace fs = std::filesystem;

std::string EnvOr(const char* name, const char* fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? value : fallback;
}

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

CliRun RunTactforce(const std::vector<std::string>& args, const std::string& stdin_text,
                    std::chrono::milliseconds timeout) {
  std::vector<std::string> argv = {BinaryPath("tactforce").string()};
  argv.insert(argv.end(), args.begin(), args.end());
  if (stdin_text.empty()) return RunProcess(argv, {}, timeout);
  const TempDir input("tactforce_stdin");
  return RunProcess(argv, {}, timeout, input.Write("stdin.txt", stdin_text));
}

CliRun Tactforce(const std::vector<std::string>& args, std::chrono::milliseconds timeout) {
  return RunTactforce(args, "", timeout);
}

std::string Describe(const CliRun& run) {
  return "exit " + std::to_string(run.exit_code) + "; stdout: " + run.out + "; stderr: " + run.err;
}

void ExpectBadInput(const CliRun& run) {
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(run.out, "");
  ASSERT_EQ(Lines(run.err).size(), 1u) << run.err;
  EXPECT_EQ(run.err.rfind("error: ", 0), 0u) << run.err;
}

void CliTest::SetUp() {
  ASSERT_TRUE(fs::exists(binary_)) << binary_;
  ASSERT_FALSE(dir_.empty()) << "no temporary directory";
}

fs::path CliTest::Write(const std::string& name, const std::string& text) {
  return temp_.Write(name, text);
}

CliRun CliTest::Tactforce(const std::vector<std::string>& args, const std::string& stdin_text) {
  return RunTactforce(args, stdin_text);
}

void CliTest::ExpectBadFlags(const std::vector<std::string>& command,
                             const std::vector<BadFlagCase>& cases) {
  for (const auto& [flags, name] : cases) {
    std::vector<std::string> args = command;
    args.insert(args.end(), flags.begin(), flags.end());
    auto r = Tactforce(args);
    ExpectBadInput(r);
    EXPECT_NE(r.err.find(name), std::string::npos) << flags[0] << ": " << r.err;
  }
}

absl::StatusOr<google::protobuf::Struct> ParseJsonObject(const std::string& text) {
  google::protobuf::Struct object;
  const auto status = google::protobuf::util::JsonStringToMessage(text, &object);
  if (!status.ok()) return absl::InvalidArgumentError(std::string(status.message()));
  return object;
}

absl::StatusOr<v1::PlanResponse> ParsePlanResponse(const std::string& text) {
  v1::PlanResponse response;
  TF_RETURN_IF_ERROR(api::ParseJson(text, &response));
  return response;
}

int ClosedPort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof address;
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0) {
    port = ntohs(address.sin_port);
  }
  close(fd);  // never listened: connections are refused
  return port;
}

std::string ExampleRequestJson() {
  return ReadFile(SourceDir() / "client/examples/sphere_pinch.json");
}

std::string RequestJson(const v1::PlanRequest& request) { return api::ToJson(request); }

v1::PlanRequest RandomRequest(uint64_t seed, int contacts, v1::Solver solver) {
  std::mt19937_64 rng(seed);
  planner::RandomGraspOptions options;
  options.min_contacts = contacts;
  options.max_contacts = contacts;
  options.infeasible_fraction = 0.0;
  const planner::RandomGrasp grasp = planner::MakeRandomGrasp(rng, options);
  v1::PlanRequest request =
      api::ToRequest(grasp.problem, planner::PlanOptions(), planner::SolverKind::kGeometric);
  request.set_solver(solver);
  return request;
}

std::unique_ptr<ServerProcess> StartServer(const std::vector<std::string>& flags) {
  std::string error;
  std::unique_ptr<ServerProcess> server = ServerProcess::Start(flags, &error);
  EXPECT_NE(server, nullptr) << "cannot start tactforce-server: " << error;
  return server;
}

std::unique_ptr<ServerProcess> RemoteCliTest::server_;

void RemoteCliTest::SetUpTestSuite() {
  if (server_ == nullptr) {
    std::string error;
    server_ = ServerProcess::Start({}, &error);
    if (server_ == nullptr) ADD_FAILURE() << "cannot start tactforce-server: " << error;
  }
}

void RemoteCliTest::TearDownTestSuite() {
  if (server_ != nullptr) {
    EXPECT_EQ(server_->Stop(), 0) << "tactforce-server stderr: " << server_->StderrText();
    server_.reset();
  }
}

void RemoteCliTest::SetUp() { ASSERT_NE(server_, nullptr) << "no server"; }

}  // namespace tactforce::testing
