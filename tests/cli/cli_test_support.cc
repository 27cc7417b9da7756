// The client tests' helpers: running the CLI, private temporary
// directories, JSON parsing, a closed loopback port, example and random
// requests, and the per-suite tactforce-server.
#include "cli_test_support.h"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <unistd.h>

#include <fstream>
#include <random>
#include <sstream>

#include <google/protobuf/util/json_util.h>

#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/planner/random_grasps.h"

namespace tactforce::cli_testing {

namespace fs = std::filesystem;

ProcessResult Tactforce(const std::vector<std::string>& args, std::chrono::milliseconds timeout) {
  std::vector<std::string> argv = {testing::BinaryPath("tactforce").string()};
  argv.insert(argv.end(), args.begin(), args.end());
  return testing::RunProcess(argv, {}, timeout);
}

std::string Describe(const ProcessResult& run) {
  return "exit " + std::to_string(run.exit_code) + "; stdout: " + run.out +
         "; stderr: " + run.err;
}

TempDir::TempDir() {
  std::string pattern = (fs::temp_directory_path() / "tactforce_cli_test.XXXXXX").string();
  if (mkdtemp(pattern.data()) != nullptr) dir_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  if (!dir_.empty()) fs::remove_all(dir_, ignored);
}

std::string TempDir::Write(const std::string& name, const std::string& text) const {
  const fs::path path = dir_ / name;
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

absl::StatusOr<google::protobuf::Struct> ParseJsonObject(const std::string& text) {
  google::protobuf::Struct object;
  const auto status = google::protobuf::util::JsonStringToMessage(text, &object);
  if (!status.ok()) return absl::InvalidArgumentError(std::string(status.message()));
  return object;
}

absl::StatusOr<v1::PlanResponse> ParsePlanResponse(const std::string& text) {
  v1::PlanResponse response;
  if (absl::Status s = api::ParseJson(text, &response); !s.ok()) return s;
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
  std::ifstream in(testing::SourceDir() / "client/examples/sphere_pinch.json", std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
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

}  // namespace tactforce::cli_testing
