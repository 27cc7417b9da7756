// One convention across `tactforce` subcommands (issue 15): numeric flags
// checked with their own names (exit 2), output folders that never mix two
// runs, a table by default and JSON with --json or --format json, "-" for
// standard input, per-command examples in --help, and the command list for
// a bare `tactforce`.
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "support/cli_fixture.h"
#include "support/test_seed.h"

namespace tactforce::testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::Not;

class CliConventionsTest : public CliTest {};

std::string Example(const std::string& name) {
  return SourceDir().string() + "/client/examples/" + name;
}

TEST_F(CliConventionsTest, EveryBadNumericFlagNamesItselfAndExitsTwo) {
  const std::string out = (dir() / "out").string();
  struct Case {
    std::vector<std::string> args;
    std::string flag;
  };
  const std::vector<Case> cases = {
      {{"friction", "t.csv", "--normal", "0,0,-1", "--window", "0"}, "--window"},
      {{"friction", "t.csv", "--normal", "0,0,-1", "--window", "-3"}, "--window"},
      {{"friction", "t.csv", "--normal", "0,0,-1", "--slip-distance", "0"}, "--slip-distance"},
      {{"friction", "t.csv", "--normal", "0,0,-1", "--min-normal-force", "-1"},
       "--min-normal-force"},
      {{"simulate", "friction", "--noise", "-1", "--out", out}, "--noise"},
      {{"simulate", "friction", "--mu", "0", "--out", out}, "--mu"},
      {{"simulate", "friction", "--trials", "0", "--out", out}, "--trials"},
      {{"simulate", "friction", "--rate", "nan", "--out", out}, "--rate"},
      {{"simulate", "friction", "--ramp", "inf", "--out", out}, "--ramp"},
      {{"simulate", "sensor", "--seconds", "0", "--out", out}, "--seconds"},
      {{"simulate", "sensor", "--rate", "-5", "--out", out}, "--rate"},
      {{"simulate", "inertia", "--contacts", "7", "--out", out}, "--contacts"},
      {{"simulate", "inertia", "--force-variance", "-1", "--out", out}, "--force-variance"},
      {{"simulate", "inertia", "--amplitude-scale", "0", "--out", out}, "--amplitude-scale"},
      {{"audit", "--csv", "r.csv", "--out", out, "--heldout", "1.5"}, "--heldout"},
      {{"audit", "--csv", "r.csv", "--out", out, "--max-causes", "-1"}, "--max-causes"},
      {{"inertia", "--csv", "l.csv", "--batch", "0"}, "--batch"},
      {{"inertia", "--csv", "l.csv", "--position-sigma", "-1"}, "--position-sigma"},
      {{"inertia", "--csv", "l.csv", "--max-iterations", "-5"}, "--max-iterations"},
      {{"experiment", "grasp", "--trials", "0"}, "--trials"},
      {{"experiment", "slope", "--tilt-rate", "0"}, "--tilt-rate"},
      {{"demo", "--repeat", "0"}, "--repeat"},
      {{"health", "--wait", "-1"}, "--wait"},
      {{"estimate", "--local", "--request", "e.json", "--format", "xml"}, "--format"},
      {{"friction", "t.csv", "--normal", "0,0,-1", "--window", "five"}, "--window"},
  };
  for (const Case& c : cases) {
    const CliRun run = Tactforce(c.args);
    SCOPED_TRACE(c.args[0] + " " + c.flag);
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_EQ(run.out, "");
    EXPECT_THAT(run.err, HasSubstr(c.flag));
    EXPECT_FALSE(fs::exists(out)) << "nothing is written on a usage error";
  }
}

TEST_F(CliConventionsTest, SimulateRefusesAFolderWithFilesUnlessForced) {
  const std::string out = (dir() / "fr").string();
  ASSERT_EQ(Tactforce({"simulate", "friction", "--trials", "3", "--out", out}).exit_code, 0);
  EXPECT_TRUE(fs::exists(out + "/trial2.csv"));
  WriteFile(out + "/notes.txt", "mine");

  // A second run into the same folder would mix two surfaces' trials.
  const CliRun refused =
      Tactforce({"simulate", "friction", "--mu", "0.3", "--trials", "2", "--out", out});
  ExpectBadInput(refused);
  EXPECT_THAT(refused.err, HasSubstr("--out"));
  EXPECT_THAT(refused.err, HasSubstr("--force"));
  EXPECT_TRUE(fs::exists(out + "/trial2.csv")) << "a refused run changes nothing";

  // --force removes only the simulation's own files, then writes the new run.
  ASSERT_EQ(
      Tactforce({"simulate", "friction", "--mu", "0.3", "--trials", "2", "--out", out, "--force"})
          .exit_code,
      0);
  EXPECT_TRUE(fs::exists(out + "/trial1.csv"));
  EXPECT_FALSE(fs::exists(out + "/trial2.csv"));
  EXPECT_EQ(ReadFile(out + "/notes.txt"), "mine");
  EXPECT_THAT(ReadFile(out + "/truth.json"), HasSubstr("\"mu\": 0.3"));
  int temporaries = 0;
  for (const auto& e : fs::directory_iterator(out))
    temporaries += e.path().filename().string().find(".tmp-") != std::string::npos;
  EXPECT_EQ(temporaries, 0);

  // The same for the sensor and inertia simulations.
  const std::string run = (dir() / "run").string();
  ASSERT_EQ(Tactforce({"simulate", "sensor", "--seconds", "2", "--out", run}).exit_code, 0);
  ExpectBadInput(Tactforce({"simulate", "sensor", "--seconds", "2", "--out", run}));
  EXPECT_EQ(Tactforce({"simulate", "sensor", "--seconds", "2", "--out", run, "--force"}).exit_code,
            0);
  const std::string inertia = (dir() / "inr").string();
  ASSERT_EQ(Tactforce({"simulate", "inertia", "--seconds", "1", "--rate", "20", "--out", inertia})
                .exit_code,
            0);
  ExpectBadInput(
      Tactforce({"simulate", "inertia", "--seconds", "1", "--rate", "20", "--out", inertia}));

  // An output folder that cannot be created is a usage error naming --out.
  const CliRun unwritable = Tactforce({"audit", "--csv", run + "/run.csv", "--out", "/proc/nope"});
  ExpectBadInput(unwritable);
  EXPECT_THAT(unwritable.err, HasSubstr("--out"));
}

TEST_F(CliConventionsTest, TableByDefaultJsonWithEitherSpelling) {
  const std::string request = Example("estimate_request.json");
  const CliRun table = Tactforce({"estimate", "--local", "--request", request});
  ASSERT_EQ(table.exit_code, 0) << table.err;
  EXPECT_THAT(table.out, HasSubstr("fx (N)"));
  EXPECT_THAT(table.out, HasSubstr("thumb"));
  const CliRun json = Tactforce({"estimate", "--local", "--request", request, "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  EXPECT_THAT(json.out, HasSubstr("\"forces\""));
  const CliRun format =
      Tactforce({"estimate", "--local", "--request", request, "--format", "json"});
  EXPECT_EQ(format.out.substr(0, 20), json.out.substr(0, 20));  // solve time differs
  ExpectBadInput(
      Tactforce({"estimate", "--local", "--request", request, "--json", "--format", "table"}));
}

TEST_F(CliConventionsTest, DashReadsStandardInputForJsonAndCsv) {
  const std::string request = ReadFile(Example("estimate_request.json"));
  const CliRun piped = Tactforce({"estimate", "--local", "--request", "-", "--json"}, request);
  ASSERT_EQ(piped.exit_code, 0) << piped.err;
  EXPECT_THAT(piped.out, HasSubstr("\"forces\""));

  const std::string out = (dir() / "fr").string();
  ASSERT_EQ(Tactforce({"simulate", "friction", "--trials", "1", "--out", out}).exit_code, 0);
  const CliRun from_file =
      Tactforce({"friction", out + "/trial0.csv", "--normal", "0,0,-1", "--json"});
  const CliRun from_stdin =
      Tactforce({"friction", "-", "--normal", "0,0,-1", "--json"}, ReadFile(out + "/trial0.csv"));
  ASSERT_EQ(from_stdin.exit_code, 0) << from_stdin.err;
  const auto mu = [](const std::string& json) { return json.substr(json.find("\"median\"")); };
  EXPECT_EQ(mu(from_stdin.out), mu(from_file.out));
  // The trial is named "<stdin>" (protobuf's JSON escapes the brackets).
  EXPECT_THAT(from_stdin.out, HasSubstr("\\u003cstdin\\u003e"));
}

TEST_F(CliConventionsTest, JsonErrorsPointAtFileLineColumnAndSuggest) {
  const std::string path =
      Write("typo.json", "{\n  \"object\": {\"mas\": 0.082},\n  \"contacts\": []\n}\n").string();
  const CliRun run = Tactforce({"estimate", "--local", "--request", path});
  ExpectBadInput(run);
  EXPECT_THAT(run.err, HasSubstr(path + ":2:14: object: unknown field 'mas'"));
  EXPECT_THAT(run.err, HasSubstr("did you mean 'mass'?"));
  const CliRun syntax =
      Tactforce({"estimate", "--local", "--request", "-"}, "{\"object\": {\"mass\" 1}}");
  ExpectBadInput(syntax);
  EXPECT_THAT(syntax.err, HasSubstr("<stdin>:1:20: expected ':'"));
}

TEST_F(CliConventionsTest, HelpShowsTheCommandsOwnExamplesAndBareTactforceListsCommands) {
  const CliRun bare = Tactforce({});
  EXPECT_EQ(bare.exit_code, 0) << bare.err;
  for (const char* command :
       {"plan", "estimate", "friction", "simulate", "audit", "inertia", "load", "health"}) {
    EXPECT_THAT(bare.out, HasSubstr(command));
  }
  const CliRun friction = Tactforce({"friction", "--help"});
  EXPECT_EQ(friction.exit_code, 0);
  EXPECT_THAT(friction.out, HasSubstr("tactforce friction /tmp/friction/trial*.csv"));
  EXPECT_THAT(friction.out, Not(HasSubstr("tactforce demo")));  // not the top-level footer
  const CliRun estimate = Tactforce({"estimate", "--help"});
  EXPECT_THAT(
      estimate.out,
      HasSubstr("tactforce estimate --local --request client/examples/estimate_request.json"));
}

// A misspelt command or flag gets the nearest names, like a misspelt JSON
// field. The misspellings are drawn (two neighbouring letters swapped) from
// a seed at test time.
TEST_F(CliConventionsTest, MisspeltCommandsAndFlagsGetDidYouMean) {
  struct Case {
    std::vector<std::string> before;  // the command path
    std::string name;                 // a real command or flag
  };
  const std::vector<Case> cases = {
      {{}, "plan"},
      {{}, "inertia"},
      {{}, "experiment"},
      {{"simulate"}, "inertia"},
      {{"experiment"}, "grasp"},
      {{"plan"}, "--local"},
      {{"plan"}, "--request"},
      {{"inertia"}, "--method"},
      {{"experiment", "grasp"}, "--trials"},
      {{"load"}, "--concurrency"},
      {{"audit"}, "--heldout"},
      {{"simulate", "inertia"}, "--contacts"},
  };
  std::mt19937 rng(::tactforce::testing::GtestSeed() + 25);
  for (const Case& c : cases) {
    std::string typo = c.name;
    const size_t first = c.name[0] == '-' ? 2 : 0;
    const size_t at =
        first + std::uniform_int_distribution<size_t>(0, c.name.size() - first - 2)(rng);
    std::swap(typo[at], typo[at + 1]);
    if (typo == c.name) typo.insert(at, "x");  // a doubled letter swaps into itself
    std::vector<std::string> args = c.before;
    args.push_back(typo);
    const CliRun run = Tactforce(args);
    SCOPED_TRACE(typo);
    EXPECT_EQ(run.exit_code, 2);
    const std::string kind = c.name[0] == '-' ? "flag" : "command";
    EXPECT_THAT(run.err, HasSubstr("unknown " + kind + " '" + typo + "'"));
    EXPECT_THAT(run.err, HasSubstr("did you mean"));
    EXPECT_THAT(run.err, HasSubstr("'" + c.name + "'"));
  }
  // Values are not flags: a negative number after a numeric flag is its value.
  const CliRun negative =
      Tactforce({"simulate", "inertia", "--force-variance", "-1", "--out", (dir() / "o").string()});
  EXPECT_THAT(negative.err, Not(HasSubstr("unknown flag")));
}

}  // namespace
}  // namespace tactforce::testing
