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

#include "support/cli_fixture.h"
#include "google/protobuf/util/message_differencer.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/json.h"
#include "tactforce/planner/examples.h"

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

using testing::CliRun;
using testing::EnvOr;
using testing::Lines;

class CliTest : public testing::CliTest {
 protected:
  static v1::PlanResponse ParseResponse(const std::string& json) {
    v1::PlanResponse response;
    absl::Status status = api::ParseJson(json, &response);
    EXPECT_TRUE(status.ok()) << status << "\n" << json;
    return response;
  }
};

TEST_F(CliTest, PlanFromFilePrintsJson) {
  const CliRun run =
      Tactforce({"plan", "--json", "--local", "--request", Write("pinch.json", kPinch).string()});
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
  const CliRun run = Tactforce({"plan", "--json", "--local", "--request", example.string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(ParseResponse(run.out).status(), v1::PLAN_STATUS_OPTIMAL);
}

// The shipped request is the built-in sphere-pinch that the demo plans, so
// the first numbers a user sees agree everywhere.
TEST_F(CliTest, ShippedExampleIsTheBuiltInSpherePinch) {
  const fs::path example = fs::path(EnvOr("TACTFORCE_SOURCE_DIR", TACTFORCE_DEFAULT_SOURCE_DIR)) /
                           "client" / "examples" / "sphere_pinch.json";
  std::ifstream in(example, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  absl::StatusOr<v1::PlanRequest> shipped = api::ParsePlanRequestJson(text.str(), example.string());
  ASSERT_TRUE(shipped.ok()) << shipped.status();
  for (const planner::ExampleGrasp& g : planner::BuiltInGrasps()) {
    if (g.name != "sphere-pinch") continue;
    // Both through the same writer, so defaults the file leaves out compare equal.
    absl::StatusOr<planner::PlanProblem> problem = api::ToProblem(*shipped);
    absl::StatusOr<planner::PlanOptions> options = api::ToOptions(*shipped);
    ASSERT_TRUE(problem.ok() && options.ok()) << problem.status() << options.status();
    const v1::PlanRequest file =
        api::ToRequest(*problem, *options, planner::SolverKind::kGeometric);
    const v1::PlanRequest builtin =
        api::ToRequest(g.problem, g.options, planner::SolverKind::kGeometric);
    EXPECT_TRUE(google::protobuf::util::MessageDifferencer::Equivalent(file, builtin))
        << "shipped:\n"
        << file.DebugString() << "built-in:\n"
        << builtin.DebugString();
    return;
  }
  FAIL() << "no built-in sphere-pinch";
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
  const CliRun run = Tactforce({"plan", "--json", "--local", "--request", "-"}, request);
  ASSERT_EQ(run.exit_code, 0) << run.err;
  const v1::PlanResponse response = ParseResponse(run.out);
  EXPECT_TRUE(response.has_cross_check()) << run.out;
  EXPECT_THAT(run.out, HasSubstr(R"("cross_check")"));
}

TEST_F(CliTest, InfeasibleIsAnAnswer) {
  const CliRun run = Tactforce({"plan", "--json", "--local", "--request", "-"}, R"({
    "object": {"mass": 1.0},
    "contacts": [{"name": "palm", "normal": {"z": 1}, "friction": 0.5,
                  "max_normal_force": 1.0}]})");
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(ParseResponse(run.out).status(), v1::PLAN_STATUS_INFEASIBLE);
}

TEST_F(CliTest, ZeroNormalIsBadInputNamingTheField) {
  const CliRun run = Tactforce({"plan", "--json", "--local", "--request", "-"}, R"({
    "object": {"mass": 0.1},
    "contacts": [{"name": "thumb", "position": {"x": 0.03}, "normal": {"x": 0},
                  "friction": 0.8}]})");
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("contacts[0].normal"));
}

TEST_F(CliTest, UnknownEnumValueIsBadInputNamingTheField) {
  const CliRun run = Tactforce({"plan", "--json", "--local", "--request", "-"},
                               R"({"contacts": [{"normal": {"z": 1}, "kind": 7}]})");
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("contacts[0].kind: unknown value 7"));
}

TEST_F(CliTest, MalformedJsonIsBadInput) {
  ExpectBadInput(Tactforce({"plan", "--json", "--local", "--request", "-"}, R"({"contacts": [)"));
  ExpectBadInput(Tactforce({"plan", "--json", "--local", "--request", "-"}, ""));
}

TEST_F(CliTest, MisspeltFieldIsBadInputNamingIt) {
  const CliRun run = Tactforce({"plan", "--json", "--local", "--request", "-"},
                               R"({"contacts": [{"normal": {"z": 1}, "frictoin": 0.5}]})");
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("frictoin"));
}

TEST_F(CliTest, MissingFileIsBadInput) {
  const CliRun run =
      Tactforce({"plan", "--json", "--local", "--request", (dir_ / "no_such_file.json").string()});
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr("no_such_file.json"));
}

TEST_F(CliTest, BadCommandLineIsBadInput) {
  ExpectBadInput(Tactforce({"plan", "--json", "--local"}));  // --request missing
  ExpectBadInput(Tactforce({"plan", "--local", "--request", "-", "--format", "xml"}));
  ExpectBadInput(Tactforce({"frobnicate"}));
  // A bare `tactforce` is not an error: it lists the commands
  // (CliConventionsTest.HelpShowsTheCommandsOwnExamplesAndBareTactforceListsCommands).
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
