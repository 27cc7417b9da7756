// `tactforce simulate inertia` + `tactforce inertia`, end to end as a user
// runs them: the JSON output is the FitInertia response in proto3 JSON with
// the documented field names; the error metrics against the truth file are
// printed; bad input names the file, line or column.
#include <gtest/gtest.h>

#include <cmath>

#include "support/cli_fixture.h"
#include "tactforce/api/json.h"
#include "tactforce/v1/inertia.pb.h"

namespace tactforce::testing {
namespace {

class InertiaCliTest : public CliTest {
 protected:
  // Simulates the paper's object (in-hand, 4 fingertips) into dir()/name.
  std::string Simulate(const std::string& name, std::vector<std::string> extra = {}) {
    const std::string out = (dir() / name).string();
    std::vector<std::string> args = {"simulate", "inertia", "--out", out, "--seconds", "5", "--seed", "3"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliRun run = Tactforce(args);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return out;
  }
};

TEST_F(InertiaCliTest, JsonIsTheFitInertiaResponseWithErrorsAgainstTheTruth) {
  const std::string sim = Simulate("sim", {"--force-variance", "0.1"});
  for (const char* method : {"baseline-ls", "factor-graph", "constrained"}) {
    const CliRun run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--truth", sim + "/truth.json",
                                  "--method", method, "--json"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    for (const char* key : {"\"mass\"", "\"com\"", "\"inertia\"", "\"ixx\"", "\"iyz\"", "\"physically_consistent\""})
      EXPECT_NE(run.out.find(key), std::string::npos) << key << " missing in " << run.out.substr(0, 300);
    v1::FitInertiaResponse response;
    ASSERT_TRUE(api::ParseJson(run.out, &response).ok()) << run.out.substr(0, 300);
    EXPECT_EQ(response.method(), std::string(method) == "constrained" ? v1::INERTIA_METHOD_CONSTRAINED
                                 : std::string(method) == "baseline-ls" ? v1::INERTIA_METHOD_BASELINE_LS
                                                                         : v1::INERTIA_METHOD_FACTOR_GRAPH);
    ASSERT_TRUE(response.has_errors()) << method;
    EXPECT_LT(std::abs(response.mass() - 1.3) / 1.3, 0.02) << method;  // the seed-table1 object
    EXPECT_NEAR(response.errors().mass_percent(), 100 * std::abs(response.mass() - 1.3) / 1.3, 1e-9);
    EXPECT_EQ(response.samples_received(), 501);
  }
}

TEST_F(InertiaCliTest, HumanOutputShowsEstimateAndErrorMetrics) {
  const std::string sim = Simulate("sim", {"--mode", "wrist", "--noise-level", "moderate"});
  EXPECT_NE(ReadFile(sim + "/inertia.csv").find("ax,ay,az"), std::string::npos);  // measured kinematics
  const CliRun run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--truth", sim + "/truth.json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  EXPECT_NE(run.out.find("method: constrained"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("physically consistent: yes"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("errors against the truth: paper metric"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("Riemannian distance"), std::string::npos) << run.out;
}

TEST_F(InertiaCliTest, HullFromACsvAndGravityFlag) {
  const std::string sim = Simulate("sim");
  // A hull far away from the true CoM (0.2, 0.5, 0.1): the constrained fit
  // must keep the CoM inside it.
  const auto hull = Write("hull.csv", "x,y,z\n-0.1,-0.1,-0.1\n0.1,-0.1,-0.1\n-0.1,0.1,-0.1\n-0.1,-0.1,0.1\n"
                                      "0.1,0.1,0.1\n");
  const CliRun run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--hull", hull.string(), "--json",
                                "--gravity", "0,0,-9.81"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FitInertiaResponse response;
  ASSERT_TRUE(api::ParseJson(run.out, &response).ok());
  EXPECT_TRUE(response.com_in_hull());
  EXPECT_LE(response.com().y(), 0.1 + 1e-6);
}

TEST_F(InertiaCliTest, BadInputNamesTheProblem) {
  const std::string header = "t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n";
  const std::string row = ",0,0,0,1,0,0,0,0,0,9.81,0,0,0\n";
  struct Case {
    std::string name, text, expect;
  };
  const std::vector<Case> cases = {
      {"missing.csv", "t,px,py,pz,qw,qx,qy,fx,fy,fz,tx,ty,tz\n0,0,0,0,1,0,0,0,0,0,0,0,0\n", "missing column(s) qz"},
      {"time.csv", header + "0" + row + "0.1" + row + "0.1" + row + "0.3" + row + "0.4" + row,
       "time.csv:4: column 't'"},
      {"few.csv", header + "0" + row + "0.1" + row + "0.2" + row, "at least"},
      {"nan.csv", header + "0" + row + "0.1,0,nan,0,1,0,0,0,0,0,9.81,0,0,0\n", "nan.csv:3"},
      {"quat.csv", header + "0" + row + "0.1,0,0,0,0,0,0,0,0,0,9.81,0,0,0\n", "near zero"},
      {"contacts.csv", "t,px,py,pz,qw,qx,qy,qz,c0_px,c0_py,c0_pz,c0_fx,c0_fy,c0_fz,c1_px,c1_py\n", "contact 1"},
  };
  for (const Case& c : cases) {
    const auto path = Write(c.name, c.text);
    const CliRun run = Tactforce({"inertia", "--csv", path.string()});
    ExpectBadInput(run);
    EXPECT_NE(run.err.find(c.expect), std::string::npos) << c.name << ": " << run.err;
  }
  const std::string sim = Simulate("sim");
  const std::string csv = sim + "/inertia.csv";
  const CliRun gravity = Tactforce({"inertia", "--csv", csv, "--gravity", "0,-9.81"});
  ExpectBadInput(gravity);
  EXPECT_NE(gravity.err.find("--gravity"), std::string::npos) << gravity.err;
  const auto truth = Write("truth.json", R"({"mass": 1.0, "com": [0, 0]})");
  const CliRun t = Tactforce({"inertia", "--csv", csv, "--truth", truth.string()});
  ExpectBadInput(t);
  EXPECT_NE(t.err.find("com"), std::string::npos) << t.err;
  // A prior whose CoM lies outside the hull.
  const auto prior = Write("prior.json", R"({"mass": 1.3, "com": [1, 1, 1], "inertia_com": [0.4, 0.13, 0.48, 0, 0, 0]})");
  const auto hull = Write("hull.csv", "x,y,z\n0,0,0\n0.1,0,0\n0,0.1,0\n0,0,0.1\n");
  const CliRun p = Tactforce({"inertia", "--csv", csv, "--prior", prior.string(), "--hull", hull.string()});
  ExpectBadInput(p);
  EXPECT_NE(p.err.find("prior.com"), std::string::npos) << p.err;
  const CliRun sim_bad = Tactforce({"simulate", "inertia", "--out", (dir() / "x").string(), "--rate", "0"});
  ExpectBadInput(sim_bad);
  EXPECT_NE(sim_bad.err.find("rate"), std::string::npos) << sim_bad.err;
}

}  // namespace
}  // namespace tactforce::testing
