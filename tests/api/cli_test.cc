// Runs the built `tactforce` binary ($TACTFORCE_BIN_DIR/tactforce).
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "tactforce/api/json.h"

namespace tactforce {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// A two-finger pinch, written with lowerCamelCase keys on purpose.
constexpr char kPinch[] = R"({
  "object": {"mass": 0.082},
  "contacts": [
    {"name": "thumb", "position": {"x": 0.03}, "normal": {"x": -1},
     "friction": 0.8, "sigma": 0.2, "minNormalForce": 0.1},
    {"name": "index", "position": {"x": -0.03}, "normal": {"x": 1},
     "friction": 0.8, "sigma": 0.2, "minNormalForce": 0.1}
  ]
})";

// $name when set and not empty, else `fallback`.
std::string EnvOr(const char* name, const char* fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? value : fallback;
}

struct CliRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) {
    if (c == '\'') {
      q += "'\\''";
    } else {
      q += c;
    }
  }
  return q + "'";
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

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override {
    binary_ = fs::path(EnvOr("TACTFORCE_BIN_DIR", TACTFORCE_DEFAULT_BIN_DIR)) / "tactforce";
    ASSERT_TRUE(fs::exists(binary_)) << binary_;
    std::string pattern = (fs::temp_directory_path() / "tactforce_cli_test.XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override {
    std::error_code ec;
    if (!dir_.empty()) fs::remove_all(dir_, ec);
  }

  fs::path Write(const std::string& name, const std::string& text) {
    WriteFile(dir_ / name, text);
    return dir_ / name;
  }

  // Runs tactforce with `args`; `stdin_text` is its standard input.
  CliRun Tactforce(const std::vector<std::string>& args, const std::string& stdin_text = "") {
    const fs::path in = Write("stdin.txt", stdin_text);
    const fs::path out = dir_ / "stdout.txt";
    const fs::path err = dir_ / "stderr.txt";
    std::string command = Quote(binary_.string());
    for (const std::string& a : args) command += " " + Quote(a);
    command += " <" + Quote(in.string()) + " >" + Quote(out.string()) + " 2>" +
               Quote(err.string());
    const int status = std::system(command.c_str());
    CliRun run;
    if (status != -1 && WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
    run.out = ReadFile(out);
    run.err = ReadFile(err);
    return run;
  }

  // A bad-input run: exit 2, nothing on stdout, one "error: " line on stderr.
  static void ExpectBadInput(const CliRun& run) {
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_EQ(run.out, "");
    ASSERT_EQ(Lines(run.err).size(), 1u) << run.err;
    EXPECT_THAT(run.err, StartsWith("error: "));
  }

  static v1::PlanResponse ParseResponse(const std::string& json) {
    v1::PlanResponse response;
    absl::Status status = api::ParseJson(json, &response);
    EXPECT_TRUE(status.ok()) << status << "\n" << json;
    return response;
  }

  fs::path binary_;
  fs::path dir_;
};

TEST_F(CliTest, PlanFromFilePrintsJson) {
  const CliRun run = Tactforce({"plan", "--local", "--request", Write("pinch.json", kPinch).string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(run.err, "");
  EXPECT_THAT(run.out, HasSubstr(R"("status": "PLAN_STATUS_OPTIMAL")"));
  EXPECT_THAT(run.out, HasSubstr(R"("normal_forces")"));  // proto field names
  const v1::PlanResponse response = ParseResponse(run.out);
  EXPECT_EQ(response.status(), v1::PLAN_STATUS_OPTIMAL);
  EXPECT_EQ(response.forces_size(), 2);
  EXPECT_EQ(response.solver(), v1::SOLVER_GEOMETRIC);
}

TEST_F(CliTest, PlanFromStdin) {
  const CliRun run = Tactforce({"plan", "--local", "--request", "-", "--format", "json"}, kPinch);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(ParseResponse(run.out).status(), v1::PLAN_STATUS_OPTIMAL);
}

TEST_F(CliTest, ShippedExampleRequestPlans) {
  const fs::path example = fs::path(EnvOr("TACTFORCE_SOURCE_DIR", TACTFORCE_DEFAULT_SOURCE_DIR)) /
                           "client" / "examples" / "sphere_pinch.json";
  const CliRun run = Tactforce({"plan", "--local", "--request", example.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(ParseResponse(run.out).status(), v1::PLAN_STATUS_OPTIMAL);
}

TEST_F(CliTest, TableFormat) {
  const CliRun run = Tactforce({"plan", "--local", "--request", "-", "--format", "table"}, kPinch);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr("status:      OPTIMAL"));
  EXPECT_THAT(run.out, HasSubstr("thumb"));
  EXPECT_THAT(run.out, HasSubstr("index"));
  EXPECT_THAT(run.out, HasSubstr("solver:      GEOMETRIC"));
}

TEST_F(CliTest, CrossCheckRequestReportsComparison) {
  std::string request = kPinch;
  request.insert(request.rfind('}'), R"(, "solver": "SOLVER_CROSS_CHECK")");
  const CliRun run = Tactforce({"plan", "--local", "--request", "-"}, request);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const v1::PlanResponse response = ParseResponse(run.out);
  EXPECT_TRUE(response.has_cross_check()) << run.out;
  EXPECT_THAT(run.out, HasSubstr(R"("cross_check")"));
}

TEST_F(CliTest, InfeasibleIsAnAnswer) {
  const CliRun run = Tactforce({"plan", "--local", "--request", "-"}, R"({
    "object": {"mass": 1.0},
    "contacts": [{"name": "palm", "normal": {"z": 1}, "friction": 0.5,
                  "max_normal_force": 1.0}]})");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(ParseResponse(run.out).status(), v1::PLAN_STATUS_INFEASIBLE);
}

TEST_F(CliTest, ZeroNormalIsBadInputNamingTheField) {
  const CliRun run = Tactforce({"plan", "--local", "--request", "-"}, R"({
    "object": {"mass": 0.1},
    "contacts": [{"name": "thumb", "position": {"x": 0.03}, "normal": {"x": 0},
                  "friction": 0.8}]})");
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("contacts[0].normal"));
}

TEST_F(CliTest, UnknownEnumValueIsBadInputNamingTheField) {
  const CliRun run = Tactforce({"plan", "--local", "--request", "-"},
                            R"({"contacts": [{"normal": {"z": 1}, "kind": 7}]})");
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("contacts[0].kind: unknown value 7"));
}

TEST_F(CliTest, MalformedJsonIsBadInput) {
  ExpectBadInput(Tactforce({"plan", "--local", "--request", "-"}, R"({"contacts": [)"));
  ExpectBadInput(Tactforce({"plan", "--local", "--request", "-"}, ""));
}

TEST_F(CliTest, MisspeltFieldIsBadInputNamingIt) {
  const CliRun run = Tactforce({"plan", "--local", "--request", "-"},
                            R"({"contacts": [{"normal": {"z": 1}, "frictoin": 0.5}]})");
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("frictoin"));
}

TEST_F(CliTest, MissingFileIsBadInput) {
  const CliRun run =
      Tactforce({"plan", "--local", "--request", (dir_ / "no_such_file.json").string()});
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("no_such_file.json"));
}

TEST_F(CliTest, ServerModeIsNotThereYet) {
  const CliRun run = Tactforce({"plan", "--request", "-"}, kPinch);
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("--local"));
}

TEST_F(CliTest, BadCommandLineIsBadInput) {
  ExpectBadInput(Tactforce({"plan", "--local"}));  // --request missing
  ExpectBadInput(Tactforce({"plan", "--local", "--request", "-", "--format", "xml"}));
  ExpectBadInput(Tactforce({"frobnicate"}));
  ExpectBadInput(Tactforce({}));
}

TEST_F(CliTest, Demo) {
  const CliRun run = Tactforce({"demo", "--repeat", "1"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  for (const char* grasp : {"sphere-pinch", "wrench-3f", "cylinder-4f"}) {
    EXPECT_THAT(run.out, HasSubstr(grasp));
  }
  EXPECT_THAT(run.out, HasSubstr("agree"));
}

TEST_F(CliTest, DemoJson) {
  const CliRun run = Tactforce({"demo", "--repeat", "1", "--format", "json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_THAT(run.out, HasSubstr(R"("grasps")"));
  EXPECT_THAT(run.out, HasSubstr(R"("speed_ratio")"));
  EXPECT_THAT(run.out, HasSubstr(R"("cross_check")"));
}

TEST_F(CliTest, HelpAndVersion) {
  CliRun run = Tactforce({"--help"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_THAT(run.out, HasSubstr("plan"));
  EXPECT_THAT(run.out, HasSubstr("demo"));
  run = Tactforce({"plan", "--help"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_THAT(run.out, HasSubstr("--request"));
  run = Tactforce({"--version"});
  EXPECT_EQ(run.exit_code, 0);
  EXPECT_THAT(run.out, StartsWith("tactforce "));
}

}  // namespace
}  // namespace tactforce
