// `tactforce experiment grasp|slope` end to end.
#include <gtest/gtest.h>

#include "support/cli_fixture.h"

namespace tactforce::testing {
namespace {

using ExperimentCliTest = CliTest;

TEST_F(ExperimentCliTest, GraspJson) {
  CliRun r = Tactforce({"experiment", "grasp", "--object", "sphere", "--trials", "1", "--feedback",
                        "estimated", "--json", "--plots", (dir() / "plots").string()});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // The JSON layout of every command (io::IndentJson).
  EXPECT_EQ(r.out.rfind("{\n  \"results\": [\n    {\n      \"object\": \"sphere\",\n      "
                        "\"feedback\": \"estimated\",\n"
                        "      \"trials\": 1,",
                        0),
            0u)
      << r.out;
  EXPECT_NE(r.out.find("\"successes\": "), std::string::npos);
  EXPECT_NE(r.out.find("\"force_error_mean\": "), std::string::npos);
  EXPECT_NE(r.out.find("\"force_error_std\": "), std::string::npos);
  const std::string svg = ReadFile(dir() / "plots" / "sphere_estimated.svg");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
}

TEST_F(ExperimentCliTest, GraspBothModesTable) {
  CliRun r =
      Tactforce({"experiment", "grasp", "--object", "cube", "--trials", "1", "--feedback", "both"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  const auto lines = Lines(r.out);
  ASSERT_GE(lines.size(), 4u) << r.out;
  EXPECT_EQ(lines[1].rfind("cube      raw", 0), 0u) << r.out;
  EXPECT_EQ(lines[2].rfind("cube      estimated", 0), 0u) << r.out;
}

TEST_F(ExperimentCliTest, SlopeJson) {
  CliRun r = Tactforce({"experiment", "slope", "--mu", "0.6", "--no-creep", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("{\n  \"results\": [\n    {\n      \"mu\": 0.6,", 0), 0u) << r.out;
  EXPECT_NE(r.out.find("\"mu_slope\": 0.60"), std::string::npos) << r.out;
}

TEST_F(ExperimentCliTest, BadInput) {
  ExpectBadInput(Tactforce({"experiment", "grasp", "--object", "banana"}));
  ExpectBadInput(Tactforce({"experiment", "grasp", "--feedback", "psychic"}));
  ExpectBadInput(Tactforce({"experiment", "grasp", "--trials", "0"}));
  ExpectBadInput(Tactforce({"experiment", "grasp", "--estimator", "guess"}));
  ExpectBadInput(
      Tactforce({"experiment", "grasp", "--sensor-model", (dir() / "missing.json").string()}));
  ExpectBadInput(Tactforce({"experiment", "slope", "--mu", "0.5,-2"}));
  ExpectBadInput(Tactforce({"experiment", "grasp", "--admittance", "sideways"}));
  ExpectBadInput(Tactforce({"experiment", "grasp", "--ideal-sensors", "--sensor-model", "m.json"}));
  ExpectBadInput(Tactforce({"experiment"}));
  CliRun r = Tactforce({"experiment", "grasp", "--object", "banana"});
  EXPECT_NE(r.err.find("--object"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "slope", "--mu", "0.5,-2"});
  EXPECT_NE(r.err.find("error: --mu: mus[1]: must be in"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace tactforce::testing
