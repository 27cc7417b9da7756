// `tactforce estimate`, `friction` and `simulate friction`, run as a user would.
#include <gtest/gtest.h>

#include "support/cli_fixture.h"
#include "tactforce/api/json.h"
#include "tactforce/v1/estimator.pb.h"

namespace tactforce::testing {
namespace {

constexpr char kEstimate[] = R"({
  "object": {"mass": 0.082},
  "contacts": [
    {"name": "thumb", "position": {"x": -0.035}, "normal": {"x": 1}, "friction": 0.8, "sigma": 0.3},
    {"name": "index", "position": {"x": 0.035}, "normal": {"x": -1}, "friction": 0.8, "sigma": 0.3}
  ],
  "readings": [1.2, 0.8],
  "method": "ESTIMATE_METHOD_NORMAL_LSQ"
})";

TEST_F(CliTest, EstimateLocalPrintsForcesInRequestOrder) {
  const CliRun run = Tactforce(
      {"estimate", "--local", "--json", "--request", Write("e.json", kEstimate).string()});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::EstimateResponse r;
  ASSERT_TRUE(api::ParseJson(run.out, &r).ok()) << run.out;
  EXPECT_EQ(r.status(), v1::ESTIMATE_STATUS_OK);
  ASSERT_EQ(r.forces_size(), 2);
  // Equilibrium: the squeeze is shared, each finger carries half the weight.
  EXPECT_NEAR(r.forces(0).x(), -r.forces(1).x(), 1e-9);
  EXPECT_NEAR(r.forces(0).z() + r.forces(1).z(), 0.082 * 9.81, 1e-9);
  EXPECT_NEAR(r.forces(0).x(), 1.0, 1e-3);  // the mean of the two readings
}

TEST_F(CliTest, EstimateBadReadingsNameTheField) {
  std::string bad = kEstimate;
  bad.replace(bad.find("[1.2, 0.8]"), 10, "[1.2]");
  ExpectBadInput(Tactforce({"estimate", "--local", "--request", Write("b.json", bad).string()}));
  EXPECT_NE(Tactforce({"estimate", "--local", "--request", Write("b.json", bad).string()})
                .err.find("readings: expected 2"),
            std::string::npos);
}

TEST_F(CliTest, SimulateThenEstimateFriction) {
  const std::string out = (dir() / "sim").string();
  const CliRun sim = Tactforce({"simulate", "friction", "--mu", "0.35", "--trials", "4", "--noise",
                                "0.05", "--seed", "3", "--out", out});
  ASSERT_EQ(sim.exit_code, 0) << sim.err;
  ASSERT_TRUE(std::filesystem::exists(out + "/truth.json"));
  const CliRun run =
      Tactforce({"friction", out + "/trial0.csv", out + "/trial1.csv", out + "/trial2.csv",
                 out + "/trial3.csv", "--normal", "0,0,-1", "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FrictionResponse r;
  ASSERT_TRUE(api::ParseJson(run.out, &r).ok()) << run.out;
  EXPECT_EQ(r.count(), 4);
  EXPECT_NEAR(r.median(), 0.35, 0.02);
  ASSERT_EQ(r.trials_size(), 4);
  EXPECT_TRUE(r.trials(0).slipped());
  EXPECT_GT(r.trials(0).slip_time(), 0.0);
  // People get a table.
  const CliRun table = Tactforce({"friction", out + "/trial0.csv", "--normal", "0,0,-1"});
  ASSERT_EQ(table.exit_code, 0);
  EXPECT_NE(table.out.find("median"), std::string::npos);
}

TEST_F(CliTest, FrictionUsesAMeshFile) {
  const std::string out = (dir() / "sim").string();
  ASSERT_EQ(
      Tactforce({"simulate", "friction", "--mu", "0.6", "--trials", "1", "--out", out}).exit_code,
      0);
  // A box top face at z = 0.02 as OBJ (counter-clockwise from outside: +z).
  const auto obj =
      Write("box.obj",
            "v -0.05 -0.05 0.02\nv 0.05 -0.05 0.02\nv 0.05 0.05 0.02\nv -0.05 0.05 0.02\n"
            "v 0 0 -0.05\nf 1 2 3 4\nf 1 5 2\nf 2 5 3\nf 3 5 4\nf 4 5 1\n");
  const CliRun run = Tactforce({"friction", out + "/trial0.csv", "--mesh", obj.string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FrictionResponse r;
  ASSERT_TRUE(api::ParseJson(run.out, &r).ok());
  EXPECT_NEAR(r.trials(0).normal().z(), -1.0, 1e-12);
  EXPECT_NEAR(r.median(), 0.6, 0.03);
}

TEST_F(CliTest, FrictionBadFilesNameTheLine) {
  const auto csv = Write("t.csv", "t,fx,fy,fz,px,py,pz\n0,1,0,-2,0,0,0\n0.1,1,x,-2,0,0,0\n");
  const CliRun run = Tactforce({"friction", csv.string(), "--normal", "0,0,-1"});
  ExpectBadInput(run);
  EXPECT_NE(run.err.find("t.csv:3: column 'fy'"), std::string::npos) << run.err;
  const auto missing = Write("m.csv", "t,fx\n0,1\n");
  ExpectBadInput(Tactforce({"friction", missing.string(), "--normal", "0,0,-1"}));
  const auto bad_obj = Write("bad.obj", "v 0 0 0\nv 1 0 0\nf 1 2 7\n");
  const CliRun mesh = Tactforce({"friction", csv.string(), "--mesh", bad_obj.string()});
  ExpectBadInput(mesh);
  ExpectBadInput(Tactforce({"friction", csv.string()}));  // neither --normal nor --mesh
}

}  // namespace
}  // namespace tactforce::testing

namespace tactforce::testing {
namespace {

TEST_F(CliTest, PlanTrajectoryLocal) {
  const std::string example = SourceDir().string() + "/client/examples/wrench_lift_trajectory.json";
  const CliRun run = Tactforce({"plan", "--json", "--local", "--trajectory", example});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::TrajectoryResponse r;
  ASSERT_TRUE(api::ParseJson(run.out, &r).ok()) << run.out;
  EXPECT_EQ(r.steps_size(), 4);
  EXPECT_EQ(r.optimal_steps(), 4);
  // Lifting needs more friction force than holding: the z forces grow.
  double hold = 0, lift = 0;
  for (const auto& f : r.steps(0).forces()) hold += f.z();
  for (const auto& f : r.steps(1).forces()) lift += f.z();
  EXPECT_NEAR(hold, 0.3 * 9.81, 1e-9);
  EXPECT_NEAR(lift, 0.3 * (9.81 + 0.5), 1e-9);
  const CliRun table = Tactforce({"plan", "--local", "--trajectory", example, "--format", "table"});
  ASSERT_EQ(table.exit_code, 0);
  EXPECT_NE(table.out.find("4 steps: 4 optimal"), std::string::npos) << table.out;
  // A rotating step without inertia names the field.
  std::string text = ReadFile(example);
  text.replace(
      text.find("\"inertia\""),
      std::string("\"inertia\": {\"ixx\": 0.0004, \"iyy\": 0.0025, \"izz\": 0.0027}").size(),
      "\"mass\": 0.3");
  const CliRun bad =
      Tactforce({"plan", "--json", "--local", "--trajectory", Write("t.json", text).string()});
  EXPECT_EQ(bad.exit_code, 2) << bad.err;
}

}  // namespace
}  // namespace tactforce::testing
