// `tactforce simulate inertia` + `tactforce inertia`, end to end as a user
// runs them: the JSON output is the FitInertia response in proto3 JSON with
// the documented field names; the error metrics against the truth file are
// printed; bad input names the file, line or column. With a mesh
// (--mesh FILE|DESCRIPTOR.json) the default method is DENSITY, the output
// carries the densities, --plot draws them, and `simulate inertia` writes
// the object's mesh for the round trip.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "inertia/test_util.h"
#include "support/cli_fixture.h"
#include "tactforce/api/inertia.h"
#include "tactforce/api/json.h"
#include "tactforce/v1/inertia.pb.h"

namespace tactforce::testing {
namespace {

class InertiaCliTest : public CliTest {
 protected:
  // Simulates the paper's object (in-hand, 4 fingertips) into dir()/name.
  std::string Simulate(const std::string& name, std::vector<std::string> extra = {}) {
    const std::string out = (dir() / name).string();
    std::vector<std::string> args = {"simulate",  "inertia", "--out",  out,
                                     "--seconds", "5",       "--seed", "3"};
    args.insert(args.end(), extra.begin(), extra.end());
    const CliRun run = Tactforce(args);
    EXPECT_EQ(run.exit_code, 0) << run.err;
    return out;
  }
};

TEST_F(InertiaCliTest, JsonIsTheFitInertiaResponseWithErrorsAgainstTheTruth) {
  const std::string sim = Simulate("sim", {"--force-variance", "0.1"});
  for (const char* method : {"baseline-ls", "factor-graph", "constrained"}) {
    const CliRun run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--truth",
                                  sim + "/truth.json", "--method", method, "--json"});
    ASSERT_EQ(run.exit_code, 0) << run.err;
    for (const char* key :
         {"\"mass\"", "\"com\"", "\"inertia\"", "\"ixx\"", "\"iyz\"", "\"physically_consistent\""})
      EXPECT_NE(run.out.find(key), std::string::npos)
          << key << " missing in " << run.out.substr(0, 300);
    v1::FitInertiaResponse response;
    ASSERT_TRUE(api::ParseJson(run.out, &response).ok()) << run.out.substr(0, 300);
    EXPECT_EQ(response.method(),
              std::string(method) == "constrained"   ? v1::INERTIA_METHOD_CONSTRAINED
              : std::string(method) == "baseline-ls" ? v1::INERTIA_METHOD_BASELINE_LS
                                                     : v1::INERTIA_METHOD_FACTOR_GRAPH);
    ASSERT_TRUE(response.has_errors()) << method;
    EXPECT_LT(std::abs(response.mass() - 1.3) / 1.3, 0.02) << method;  // the seed-table1 object
    EXPECT_NEAR(response.errors().mass_percent(), 100 * std::abs(response.mass() - 1.3) / 1.3,
                1e-9);
    EXPECT_EQ(response.samples_received(), 501);
  }
}

TEST_F(InertiaCliTest, HumanOutputShowsEstimateAndErrorMetrics) {
  const std::string sim = Simulate("sim", {"--mode", "wrist", "--noise-level", "moderate"});
  EXPECT_NE(ReadFile(sim + "/inertia.csv").find("ax,ay,az"),
            std::string::npos);  // measured kinematics
  const CliRun run =
      Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--truth", sim + "/truth.json"});
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
  const auto hull = Write("hull.csv",
                          "x,y,z\n-0.1,-0.1,-0.1\n0.1,-0.1,-0.1\n-0.1,0.1,-0.1\n-0.1,-0.1,0.1\n"
                          "0.1,0.1,0.1\n");
  const CliRun run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--hull", hull.string(),
                                "--json", "--gravity", "0,0,-9.81"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FitInertiaResponse response;
  ASSERT_TRUE(api::ParseJson(run.out, &response).ok());
  EXPECT_TRUE(response.com_in_hull());
  EXPECT_LE(response.com().y(), 0.1 + 1e-6);
}

// --fg-variant selects the factor graph of the paper's ablation; the
// response's first factor-graph note names it.
TEST_F(InertiaCliTest, FactorGraphVariantFlag) {
  const std::string sim = Simulate("sim", {"--mode", "wrist"});
  for (const char* variant : {"baseline-fg", "fg-no-c", "fg-c", "fg-c-g"}) {
    std::vector<std::string> args = {"inertia",  "--csv",        sim + "/inertia.csv",
                                     "--method", "factor-graph", "--fg-variant",
                                     variant,    "--json"};
    if (std::string(variant) == "fg-c-g") args.insert(args.end(), {"--prior", sim + "/truth.json"});
    const CliRun run = Tactforce(args);
    ASSERT_EQ(run.exit_code, 0) << variant << ": " << run.err;
    v1::FitInertiaResponse response;
    ASSERT_TRUE(api::ParseJson(run.out, &response).ok()) << run.out.substr(0, 300);
    bool named = false;
    for (const std::string& note : response.notes())
      named |= note.rfind(absl::StrCat("factor-graph variant ", variant, ":"), 0) == 0;
    EXPECT_TRUE(named) << variant;
  }
  // Bad input: exit 2, the flag or field named, nothing on stdout.
  CliRun run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--method", "factor-graph",
                          "--fg-variant", "fg-x"});
  ExpectBadInput(run);
  EXPECT_NE(run.err.find("--fg-variant"), std::string::npos) << run.err;
  run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--method", "factor-graph",
                   "--fg-variant", "fg-c-g"});
  ExpectBadInput(run);
  EXPECT_NE(run.err.find("--fg-variant fg-c-g needs --prior FILE"), std::string::npos) << run.err;
}

// InertiaFitOptions.fg_variant through proto3 JSON and back to the library.
TEST(InertiaFgVariantProto, RoundTrip) {
  for (inertia::FactorGraphVariant v :
       {inertia::FactorGraphVariant::kBaselineFg, inertia::FactorGraphVariant::kNoConstraint,
        inertia::FactorGraphVariant::kConstraint, inertia::FactorGraphVariant::kConstraintPrior}) {
    v1::InertiaFitOptions o;
    o.set_method(v1::INERTIA_METHOD_FACTOR_GRAPH);
    o.set_fg_variant(api::FactorGraphVariantToProto(v));
    o.mutable_prior()->mutable_params()->set_mass(1.0);
    o.mutable_prior()->mutable_params()->mutable_inertia()->set_ixx(0.01);
    o.mutable_prior()->mutable_params()->mutable_inertia()->set_iyy(0.01);
    o.mutable_prior()->mutable_params()->mutable_inertia()->set_izz(0.01);
    v1::InertiaFitOptions back;
    ASSERT_TRUE(api::ParseJson(api::ToJson(o), &back).ok());
    absl::StatusOr<inertia::InertiaOptions> lib = api::InertiaOptionsFromProto(back);
    ASSERT_TRUE(lib.ok()) << lib.status();
    EXPECT_EQ(lib->factor_graph.variant, v);
  }
  v1::InertiaFitOptions unspecified;
  EXPECT_EQ(api::InertiaOptionsFromProto(unspecified)->factor_graph.variant,
            inertia::FactorGraphVariant::kConstraint);
  v1::InertiaFitOptions bad;
  bad.set_fg_variant(static_cast<v1::FactorGraphVariant>(17));
  absl::StatusOr<inertia::InertiaOptions> lib = api::InertiaOptionsFromProto(bad);
  ASSERT_FALSE(lib.ok());
  EXPECT_NE(lib.status().message().find("options.fg_variant"), std::string::npos) << lib.status();
  v1::InertiaFitOptions no_prior;
  no_prior.set_method(v1::INERTIA_METHOD_FACTOR_GRAPH);
  no_prior.set_fg_variant(v1::FACTOR_GRAPH_VARIANT_C_G);
  lib = api::InertiaOptionsFromProto(no_prior);
  ASSERT_FALSE(lib.ok());
  EXPECT_NE(lib.status().message().find("options.prior"), std::string::npos) << lib.status();
}

TEST_F(InertiaCliTest, BadInputNamesTheProblem) {
  const std::string header = "t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n";
  const std::string row = ",0,0,0,1,0,0,0,0,0,9.81,0,0,0\n";
  struct Case {
    std::string name, text, expect;
  };
  const std::vector<Case> cases = {
      {"missing.csv", "t,px,py,pz,qw,qx,qy,fx,fy,fz,tx,ty,tz\n0,0,0,0,1,0,0,0,0,0,0,0,0\n",
       "missing column(s) qz"},
      {"time.csv", header + "0" + row + "0.1" + row + "0.1" + row + "0.3" + row + "0.4" + row,
       "time.csv:4: column 't'"},
      {"few.csv", header + "0" + row + "0.1" + row + "0.2" + row, "at least"},
      {"nan.csv", header + "0" + row + "0.1,0,nan,0,1,0,0,0,0,0,9.81,0,0,0\n", "nan.csv:3"},
      {"quat.csv", header + "0" + row + "0.1,0,0,0,0,0,0,0,0,0,9.81,0,0,0\n", "near zero"},
      {"contacts.csv", "t,px,py,pz,qw,qx,qy,qz,c0_px,c0_py,c0_pz,c0_fx,c0_fy,c0_fz,c1_px,c1_py\n",
       "contact 1"},
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
  const auto prior =
      Write("prior.json",
            R"({"mass": 1.3, "com": [1, 1, 1], "inertia_com": [0.4, 0.13, 0.48, 0, 0, 0]})");
  const auto hull = Write("hull.csv", "x,y,z\n0,0,0\n0.1,0,0\n0,0.1,0\n0,0,0.1\n");
  const CliRun p =
      Tactforce({"inertia", "--csv", csv, "--prior", prior.string(), "--hull", hull.string()});
  ExpectBadInput(p);
  EXPECT_NE(p.err.find("prior.com"), std::string::npos) << p.err;
  const CliRun sim_bad =
      Tactforce({"simulate", "inertia", "--out", (dir() / "x").string(), "--rate", "0"});
  ExpectBadInput(sim_bad);
  EXPECT_NE(sim_bad.err.find("rate"), std::string::npos) << sim_bad.err;
}

// An ASCII STL of the box [-a, a]^3 (outward winding); `skip` drops one of
// its 12 triangles (an open mesh), `flip` turns it inside out.
std::string BoxStl(double a, int skip = -1, bool flip = false) {
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                           {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  auto corner = [a](int i) {
    return absl::StrFormat("%g %g %g", i & 1 ? a : -a, i & 2 ? a : -a, i & 4 ? a : -a);
  };
  std::string out = "solid box\n";
  int t = 0;
  for (const auto& q : quads) {
    for (const auto& tri :
         {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      if (t++ == skip) continue;
      out += "facet normal 0 0 0\nouter loop\n";
      for (int k : flip ? std::array<int, 3>{tri[0], tri[2], tri[1]} : tri)
        out += "vertex " + corner(k) + "\n";
      out += "endloop\nendfacet\n";
    }
  }
  return out + "endsolid box\n";
}

class InertiaMeshCliTest : public InertiaCliTest {
 protected:
  void SetUp() override {
    InertiaCliTest::SetUp();
    const auto shared = inertia::testing::SharedInertiaDir();
    if (shared) shared_ = *shared;
  }
  std::string shared_;
};

// The shared Pliers through their descriptor (CAD mm, CAD frame): DENSITY is
// the default with a mesh, the text output says density-realizable, the
// JSON carries the new fields, and --plot writes the SVG.
TEST_F(InertiaMeshCliTest, SharedToolDescriptorGivesADensityRealizableFit) {
  if (shared_.empty()) GTEST_SKIP() << "../shared/data/inertia is absent";
  const std::string csv = shared_ + "/Pliers.csv", mesh = shared_ + "/Pliers.mesh.json";
  const std::string truth = shared_ + "/Pliers.truth.json";
  const std::string plot = (dir() / "pliers.svg").string();
  const CliRun text =
      Tactforce({"inertia", "--csv", csv, "--mesh", mesh, "--truth", truth, "--plot", plot});
  ASSERT_EQ(text.exit_code, 0) << text.err;
  EXPECT_NE(text.out.find("method: density"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("density-realizable: yes"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("kg/m^3"), std::string::npos) << text.out;
  EXPECT_NE(text.out.find("mesh: "), std::string::npos) << text.out;  // the mesh check line
  EXPECT_NE(text.out.find("Riemannian distance"), std::string::npos) << text.out;
  const std::string svg = ReadFile(plot);
  EXPECT_NE(svg.find("<svg"), std::string::npos) << svg.substr(0, 200);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);

  const CliRun json =
      Tactforce({"inertia", "--csv", csv, "--mesh", mesh, "--truth", truth, "--json"});
  ASSERT_EQ(json.exit_code, 0) << json.err;
  for (const char* key :
       {"\"densities\"", "\"density_realizable\"", "\"mesh_check\"", "\"standard_error\"",
        "\"density_regularization_rule\"", "\"heldout_residual_ratio\"", "\"mesh_contradicted\""})
    EXPECT_NE(json.out.find(key), std::string::npos)
        << key << " missing in " << json.out.substr(0, 400);
  v1::FitInertiaResponse response;
  ASSERT_TRUE(api::ParseJson(json.out, &response).ok()) << json.out.substr(0, 300);
  EXPECT_EQ(response.method(), v1::INERTIA_METHOD_DENSITY);
  EXPECT_TRUE(response.density_realizable());
  EXPECT_FALSE(response.mesh_contradicted()) << response.mesh_contradiction();
  ASSERT_GT(response.densities_size(), 0);
  for (const v1::DensityRegion& d : response.densities()) {
    EXPECT_GE(d.density(), 0.0) << d.label();
    EXPECT_GT(d.volume(), 0.0) << d.label();
  }
  EXPECT_TRUE(response.mesh_check().closed());
  EXPECT_GT(response.mesh_check().volume(), 0.0);
  EXPECT_GT(response.mesh_check().faces(), 1000);
  // Noise-free data of a one-material tool: close to the truth.
  ASSERT_TRUE(response.has_errors());
  EXPECT_LT(response.errors().mass_percent(), 0.5);
  EXPECT_LT(response.errors().riemannian(), 0.1);

  // --method constrained with the mesh: the mesh is the prior, no densities.
  const CliRun constrained =
      Tactforce({"inertia", "--csv", csv, "--mesh", mesh, "--method", "constrained", "--json"});
  ASSERT_EQ(constrained.exit_code, 0) << constrained.err;
  ASSERT_TRUE(api::ParseJson(constrained.out, &response).ok());
  EXPECT_EQ(response.method(), v1::INERTIA_METHOD_CONSTRAINED);
  EXPECT_FALSE(response.density_realizable());
  EXPECT_EQ(response.densities_size(), 0);
}

// `simulate inertia --object box` writes mesh.stl beside inertia.csv; the
// fit with it is density-realizable and finds the box.
TEST_F(InertiaMeshCliTest, SimulatedObjectMeshRoundTrips) {
  const std::string sim = Simulate("box", {"--object", "box", "--mode", "wrist", "--kinematics"});
  ASSERT_TRUE(std::filesystem::exists(sim + "/mesh.stl"));
  const std::string stl = ReadFile(sim + "/mesh.stl");
  ASSERT_EQ(stl.size(), 84u + 50u * 12u);  // binary STL of the 12 box triangles
  const std::string plot = (dir() / "box.svg").string();
  const CliRun run = Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--mesh",
                                sim + "/mesh.stl", "--truth", sim + "/truth.json", "--regions",
                                "grid", "--target-regions", "8", "--json", "--plot", plot});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FitInertiaResponse response;
  ASSERT_TRUE(api::ParseJson(run.out, &response).ok()) << run.out.substr(0, 300);
  EXPECT_EQ(response.method(), v1::INERTIA_METHOD_DENSITY);
  EXPECT_TRUE(response.density_realizable());
  EXPECT_EQ(response.region_scheme(), v1::REGION_SCHEME_GRID);
  EXPECT_GE(response.densities_size(), 2);
  EXPECT_EQ(response.mesh_check().faces(), 12);
  ASSERT_TRUE(response.has_errors());
  EXPECT_LT(response.errors().mass_percent(), 0.1);
  EXPECT_LT(response.errors().riemannian(), 0.05);
  EXPECT_NE(ReadFile(plot).find("<svg"), std::string::npos);

  // The seed-table1 object (in-hand, the default) has a mesh as well.
  const std::string seed = Simulate("seed");
  EXPECT_TRUE(std::filesystem::exists(seed + "/mesh.stl"));
  const CliRun fit =
      Tactforce({"inertia", "--csv", seed + "/inertia.csv", "--mesh", seed + "/mesh.stl"});
  ASSERT_EQ(fit.exit_code, 0) << fit.err;
  EXPECT_NE(fit.out.find("density-realizable: yes"), std::string::npos) << fit.out;
}

TEST_F(InertiaMeshCliTest, BadMeshInputNamesTheFileOrFlag) {
  const std::string sim = Simulate("sim");
  const std::string csv = sim + "/inertia.csv";
  const std::string box = Write("box.stl", BoxStl(0.05)).string();
  struct Case {
    std::vector<std::string> flags;
    std::string expect;
  };
  const std::vector<Case> cases = {
      {{"--mesh", box, "--mesh-scale", "0"}, "--mesh-scale: must be > 0 (got 0)"},
      {{"--mesh", box, "--mesh-scale", "big"}, "--mesh-scale: 'big' is not a number"},
      {{"--mesh", box, "--mesh-pose", "1,2"},
       "--mesh-pose: expected 7 numbers x,y,z,qw,qx,qy,qz (got 2 in '1,2')"},
      {{"--mesh", box, "--mesh-pose", "0,0,0,1,0,zero,0"}, "--mesh-pose: 'zero' is not a number"},
      {{"--mesh", box, "--mesh-pose", "0,0,0,0,0,0,0"},
       "--mesh-pose: quaternion qw,qx,qy,qz has norm 0"},
      {{"--mesh", (dir() / "nope.stl").string()}, "nope.stl' does not exist"},
      {{"--mesh", Write("open.stl", BoxStl(0.05, 3)).string()},
       "open.stl: 3 boundary edges: the mesh is not closed"},
      {{"--mesh", Write("inside_out.stl", BoxStl(0.05, -1, true)).string()}, "flip the winding"},
      {{"--mesh", Write("bad.mesh.json", R"({"mesh": "box.stl", "colour": "red"})").string()},
       "bad.mesh.json: unknown key 'colour'"},
      {{"--mesh", Write("nomesh.json", R"({"scale": 0.001})").string()},
       "nomesh.json: missing key 'mesh'"},
      {{"--mesh", Write("mesh.step", "solid").string()}, "mesh.step: unknown mesh format"},
      {{"--mesh", Write("junk.ply", "ply\nthis is not a mesh\n").string()}, "junk.ply"},
      {{"--mesh", box, "--plot", (dir() / "no_such_dir" / "x.svg").string()}, "--plot: directory"},
      {{"--mesh", box, "--target-regions", "600"}, "--target-regions: must be in 1..100"},
      {{"--mesh", box, "--density-regularization", "-1"}, "--density-regularization: must be >= 0"},
      {{"--method", "density"}, "the density method needs the object's closed mesh (--mesh)"},
      {{"--mesh-scale", "2"}, "--mesh"},  // needs --mesh (CLI11)
  };
  for (const Case& c : cases) {
    std::vector<std::string> args = {"inertia", "--csv", csv};
    args.insert(args.end(), c.flags.begin(), c.flags.end());
    const CliRun run = Tactforce(args);
    ExpectBadInput(run);
    EXPECT_NE(run.err.find(c.expect), std::string::npos) << c.flags.back() << ": " << run.err;
  }
}

// The hull option reads PLY (and descriptors) through the library reader.
TEST_F(InertiaMeshCliTest, HullFromAPlyMesh) {
  const std::string sim = Simulate("sim");
  const auto ply = Write(
      "hull.ply",
      "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
      "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n"
      "-0.1 -0.1 -0.1\n0.1 -0.1 -0.1\n-0.1 0.1 -0.1\n0.1 0.1 -0.1\n"
      "-0.1 -0.1 0.1\n0.1 -0.1 0.1\n-0.1 0.1 0.1\n0.1 0.1 0.1\n"
      "3 0 2 3\n3 0 3 1\n3 4 5 7\n3 4 7 6\n3 0 1 5\n3 0 5 4\n"
      "3 2 6 7\n3 2 7 3\n3 0 4 6\n3 0 6 2\n3 1 3 7\n3 1 7 5\n");
  const CliRun run =
      Tactforce({"inertia", "--csv", sim + "/inertia.csv", "--hull", ply.string(), "--json"});
  ASSERT_EQ(run.exit_code, 0) << run.err;
  v1::FitInertiaResponse response;
  ASSERT_TRUE(api::ParseJson(run.out, &response).ok());
  EXPECT_EQ(response.method(), v1::INERTIA_METHOD_CONSTRAINED);  // --hull is not --mesh
  EXPECT_TRUE(response.com_in_hull());
  EXPECT_LE(response.com().y(), 0.1 + 1e-6);  // the true CoM (0.2, 0.5, 0.1) is outside
}

}  // namespace
}  // namespace tactforce::testing
