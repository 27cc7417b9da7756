// What every `tactforce` command prints and names: one JSON layout (two
// spaces per level) for every command that prints JSON, `plan
// --friction-probe` locally and through the server, and the example files
// each command's --help names exist.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "support/cli_fixture.h"
#include "tactforce/api/json.h"
#include "tactforce/io/json.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::cli_testing {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

// Lines of `text` not indented by two spaces per open bracket (strings
// skipped), as "line N: ..."; empty when every line is.
std::vector<std::string> IndentationErrors(const std::string& text) {
  std::vector<std::string> errors;
  int depth = 0, number = 0;
  size_t start = 0;
  while (start < text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    ++number;
    const size_t spaces = line.find_first_not_of(' ');
    if (spaces == std::string::npos) continue;
    const int expected = depth - ((line[spaces] == '}' || line[spaces] == ']') ? 1 : 0);
    if (static_cast<int>(spaces) != 2 * expected) {
      errors.push_back(absl::StrFormat("line %d: %d spaces, expected %d: %s", number, spaces,
                                       2 * expected, line));
    }
    io::JsonStringTracker strings;
    for (size_t i = spaces; i < line.size(); ++i) {
      const char c = line[i];
      if (strings.InString(c)) {
        continue;
      } else if (c == '{' || c == '[') {
        ++depth;
      } else if (c == '}' || c == ']') {
        --depth;
      }
    }
  }
  return errors;
}

std::string Example(const std::string& name) {
  return (testing::SourceDir() / "client" / "examples" / name).string();
}

class OutputTest : public RemoteCliTest {};

TEST(IndentationCheckTest, FlagsOneSpaceAndOneLineJson) {
  EXPECT_TRUE(IndentationErrors("{\n  \"a\": [\n    1\n  ],\n  \"b\": \"{[\"\n}\n").empty());
  EXPECT_FALSE(IndentationErrors("{\n \"a\": 1\n}\n").empty());
  EXPECT_FALSE(IndentationErrors("{\"a\": {\n\"b\": 1}}\n").empty());
}

// Every command that prints JSON, in the one layout.
TEST_F(OutputTest, EveryJsonCommandIndentsByTwoSpaces) {
  const ProcessResult sim = Tactforce({"simulate", "friction", "--mu", "0.6", "--trials", "3",
                                       "--noise", "0.05", "--seed", "7", "--out", dir_.Path("fr")});
  ASSERT_EQ(sim.exit_code, 0) << Describe(sim);
  const std::vector<std::vector<std::string>> commands = {
      {"plan", "--local", "--request", Example("sphere_pinch.json"), "--json"},
      {"plan", "--server", address(), "--request", Example("sphere_pinch.json"), "--format",
       "json"},
      {"plan", "--local", "--trajectory", Example("wrench_lift_trajectory.json"), "--json"},
      {"plan", "--local", "--friction-probe", Example("friction_probe.json"), "--json"},
      {"plan", "--server", address(), "--friction-probe", Example("friction_probe.json"), "--json"},
      {"estimate", "--local", "--request", Example("estimate_request.json"), "--json"},
      {"friction", dir_.Path("fr/trial0.csv"), dir_.Path("fr/trial1.csv"),
       dir_.Path("fr/trial2.csv"), "--normal", "0,0,-1", "--json"},
      {"inertia", "--csv", Example("inertia_log.csv"), "--hull", Example("inertia_box.stl"),
       "--json"},
      {"audit", "--reference", Example("reference.csv"), "--reading", Example("reading.csv"),
       "--out", dir_.Path("audit"), "--json"},
      {"health", "--server", address(), "--json"},
      {"load", "--target", address(), "--rpc", "health", "--requests", "20", "--concurrency", "2",
       "--json"},
      {"demo", "--repeat", "1", "--json"},
      {"experiment", "slope", "--mu", "0.6", "--no-creep", "--json"},
      {"experiment", "probe", "--mu", "0.6", "--trials", "1", "--no-progress", "--json"},
      {"experiment", "inhand", "--duration", "1", "--no-progress", "--out", dir_.Path("inhand"),
       "--json"},
      {"experiment", "ablation", "--seeds", "1", "--sources", "sim-0.25", "--methods",
       "constrained", "--duration", "1.5", "--no-progress", "--json"},
  };
  for (const std::vector<std::string>& args : commands) {
    const std::string name = absl::StrCat(args[0], " ", args[1], " ", args[2]);
    const ProcessResult run = Tactforce(args, std::chrono::seconds(120));
    ASSERT_EQ(run.exit_code, 0) << name << ": " << Describe(run);
    EXPECT_TRUE(ParseJsonObject(run.out).ok()) << name << ":\n" << run.out;
    EXPECT_THAT(IndentationErrors(run.out), ::testing::IsEmpty()) << name << ":\n"
                                                                  << run.out.substr(0, 600);
    EXPECT_EQ(run.out.substr(0, 4), "{\n  ") << name;  // never one line
  }
}

// A probe drawn from a seed: --local and --server give the same plan, and
// the probe's force follows the requested ramp.
TEST_F(OutputTest, FrictionProbeLocalAndRemoteAgreeOnADrawnRamp) {
  std::mt19937_64 rng(25);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    const double initial = 1.5 + 1.5 * unit(rng), final = 0.5 + (initial - 0.7) * unit(rng);
    const double ramp = 0.5 + 1.5 * unit(rng), rate = 5 + 15 * unit(rng),
                 tangential = 0.1 + 0.5 * unit(rng);
    const std::string request = absl::StrFormat(
        R"({"plan": %s, "position": {"z": 0.012}, "normal": {"z": -1}, "tangent": {"x": 1},
            "tangential_force": %.17g, "initial_normal_force": %.17g, "final_normal_force": %.17g,
            "ramp_rate": %.17g, "sample_rate": %.17g})",
        api::ToJson(RandomRequest(trial, 3, v1::SOLVER_GEOMETRIC)), tangential, initial, final,
        ramp, rate);
    const std::string path = dir_.Write("probe.json", request);
    const ProcessResult local = Tactforce({"plan", "--local", "--friction-probe", path, "--json"});
    const ProcessResult remote =
        Tactforce({"plan", "--server", address(), "--friction-probe", path, "--json"});
    ASSERT_EQ(local.exit_code, 0) << Describe(local);
    ASSERT_EQ(remote.exit_code, 0) << Describe(remote);
    v1::FrictionProbeResponse a, b;
    ASSERT_TRUE(api::ParseJson(local.out, &a).ok()) << local.out;
    ASSERT_TRUE(api::ParseJson(remote.out, &b).ok()) << remote.out;
    const int count = static_cast<int>(std::floor((initial - final) / ramp * rate)) + 1;
    ASSERT_EQ(a.times_size(), count);
    ASSERT_EQ(b.times_size(), count);
    ASSERT_EQ(a.holding().steps_size(), count);
    for (int k = 0; k < count; ++k) {
      EXPECT_NEAR(-a.probe_forces(k).z(), std::max(final, initial - ramp * a.times(k)), 1e-9);
      EXPECT_NEAR(a.probe_forces(k).x(), tangential, 1e-12);
      EXPECT_EQ(a.probe_forces(k).z(), b.probe_forces(k).z());
      EXPECT_EQ(a.holding().steps(k).status(), b.holding().steps(k).status());
      for (int i = 0; i < a.holding().steps(k).forces_size(); ++i) {
        EXPECT_NEAR(a.holding().steps(k).forces(i).x(), b.holding().steps(k).forces(i).x(), 1e-12);
      }
    }
  }
}

TEST_F(OutputTest, FrictionProbeTableAndBadInput) {
  const ProcessResult table =
      Tactforce({"plan", "--local", "--friction-probe", Example("friction_probe.json")});
  ASSERT_EQ(table.exit_code, 0) << Describe(table);
  EXPECT_THAT(table.out, HasSubstr("probe force (N)"));
  EXPECT_THAT(table.out, HasSubstr("samples: "));
  const std::string bad = dir_.Write("bad_probe.json", R"({"plan": {}, "ramp_rate": 0})");
  for (const std::vector<std::string>& args :
       {std::vector<std::string>{"plan", "--local", "--friction-probe", bad},
        {"plan", "--local", "--friction-probe", dir_.Path("missing.json")},
        {"plan", "--local", "--friction-probe", Example("friction_probe.json"), "--request",
         Example("sphere_pinch.json")},
        {"plan", "--local", "--friction-probe", Example("friction_probe.json"), "--plot",
         dir_.Path("p.svg")}}) {
    const ProcessResult run = Tactforce(args);
    EXPECT_EQ(run.exit_code, 2) << Describe(run);
    EXPECT_EQ(run.out, "") << Describe(run);
    EXPECT_FALSE(fs::exists(dir_.Path("p.svg")));
  }
}

// Every client/examples/ path that a command's --help names is shipped.
TEST_F(OutputTest, HelpExamplesNameShippedFiles) {
  const std::vector<std::vector<std::string>> commands = {{"plan"},
                                                          {"estimate"},
                                                          {"friction"},
                                                          {"inertia"},
                                                          {"audit"},
                                                          {"simulate", "sensor"},
                                                          {"simulate", "friction"},
                                                          {"simulate", "inertia"},
                                                          {"load"},
                                                          {"health"},
                                                          {"demo"},
                                                          {"experiment", "grasp"},
                                                          {"experiment", "slope"}};
  const std::regex example(R"(client/examples/[A-Za-z0-9_.\-]+)");
  int named = 0;
  for (std::vector<std::string> args : commands) {
    args.push_back("--help");
    const ProcessResult run = Tactforce(args);
    ASSERT_EQ(run.exit_code, 0) << Describe(run);
    for (std::sregex_iterator it(run.out.begin(), run.out.end(), example), end; it != end; ++it) {
      ++named;
      EXPECT_TRUE(fs::exists(testing::SourceDir() / it->str()))
          << args[0] << " --help names " << it->str();
    }
  }
  EXPECT_GT(named, 5);
}

}  // namespace
}  // namespace tactforce::cli_testing
