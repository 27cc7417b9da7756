// Friction probed inside a grasp (experiment/probe.h) and
// `tactforce experiment probe` end to end. Surfaces and an object are drawn
// from a fixed seed at test time.
#include <cmath>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/cli_fixture.h"
#include "tactforce/experiment/probe.h"
#include "tactforce/io/json.h"
#include "tactforce/io/mesh.h"

namespace tactforce::experiment {
namespace {

// $PROBE_SEED draws other surfaces and objects (a robustness check by hand).
const uint64_t kTestSeed =
    std::getenv("PROBE_SEED") ? std::strtoull(std::getenv("PROBE_SEED"), nullptr, 10) : 20261127;

// A box drawn at test time: edges 5-10 cm, 0.08-0.3 kg, CoM up to 5 mm off-centre.
ProbeObject DrawObject(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> edge(0.05, 0.10), mass(0.08, 0.3), off(-0.005, 0.005);
  ProbeObject o;
  o.name = "drawn";
  o.size = Eigen::Vector3d(edge(rng), edge(rng), edge(rng));
  o.mass = mass(rng);
  o.com_offset = Eigen::Vector3d(off(rng), off(rng), off(rng));
  return o;
}

TEST(ProbeData, BuiltInSurfacesAndObjectsAreValid) {
  ASSERT_GE(BuiltInSurfaces().size(), 10u);
  for (const SurfacePair& s : BuiltInSurfaces()) {
    EXPECT_GE(s.mu, 0.3) << s.name;
    EXPECT_LE(s.mu, 1.0) << s.name;
  }
  EXPECT_TRUE(ValidateSurfaces(BuiltInSurfaces()).ok());
  for (const ProbeObject& o : BuiltInProbeObjects())
    EXPECT_TRUE(ValidateProbeObject(o).ok()) << o.name;
  EXPECT_EQ(FindProbeObject("nope").status().code(), absl::StatusCode::kNotFound);
}

TEST(ProbeData, BoxMeshIsAClosedSolidOfTheBoxVolume) {
  const Eigen::Vector3d size(0.07, 0.05, 0.03);
  const io::MeshCheck check = io::CheckMesh(BoxMesh(size));
  EXPECT_TRUE(check.closed);
  EXPECT_TRUE(check.consistently_oriented);
  EXPECT_NEAR(check.volume, size.prod(), 1e-12);
  // The top face's inward normal is -z.
  const io::NearestTriangle top =
      io::FindNearestTriangle(BoxMesh(size), Eigen::Vector3d(0.01, 0, 0.015));
  EXPECT_NEAR(top.inward_normal.z(), -1, 1e-12);
}

TEST(ProbeData, JsonObjectErrorsNameTheField) {
  auto ok = ProbeObjectFromJson(
      R"({"name": "b", "size": [0.06, 0.05, 0.04], "mass": 0.1, "com_offset": [0, 0.001, 0]})",
      "b.json");
  ASSERT_TRUE(ok.ok()) << ok.status();
  EXPECT_DOUBLE_EQ(ok->com_offset.y(), 0.001);
  auto expect_error = [](const std::string& text, const std::string& field) {
    auto r = ProbeObjectFromJson(text, "b.json");
    ASSERT_FALSE(r.ok()) << text;
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find(field), std::string::npos) << r.status().message();
  };
  expect_error(R"({"size": [0.06, 0.05, 0.04], "mass": -0.1})", "mass");
  expect_error(R"({"size": [0.06, 0.05], "mass": 0.1})", "size");
  expect_error(R"({"size": [0.06, 0.05, 1.0], "mass": 0.1})", "size[2]");
  expect_error(R"({"size": [0.06, 0.05, 0.04]})", "mass");
  expect_error(R"({"size": [0.06, 0.05, 0.04], "mass": 0.1, "colour": 1})", "colour");
  expect_error(R"({"size": [0.06, 0.05, 0.04], "mass": 0.1, "com_offset": [0.05, 0, 0]})",
               "com_offset[0]");
  expect_error(R"({"size": [0.06, 0.05, 0.04], "mass": 0.1,})", "b.json:1");
}

TEST(ProbeData, ConfigErrorsNameTheField) {
  ProbeConfig c;
  c.hold_scale = 0;
  EXPECT_NE(ValidateProbeConfig(c).message().find("hold_scale"), std::string::npos);
  c = ProbeConfig();
  c.force_sigma = -1;
  EXPECT_NE(ValidateProbeConfig(c).message().find("force_sigma"), std::string::npos);
  EXPECT_NE(ValidateSurfaces({{"x", 0.5}, {"y", 3}}).message().find("surfaces[1].mu"),
            std::string::npos);
  EXPECT_FALSE(RunProbeExperiment(ProbeConfig(), {{"x", 0.5}}, 0).ok());
}

// Surfaces with mu drawn in [0.2, 1.2] and a drawn box, in the air and on a
// table, with noise-free force sensing (the mechanics: grasp, tracking, mesh
// normal, eq. 5): every trial valid with slip detected, the normal from the
// top face, and the estimate within 0.03 of the slope method on the same pair.
TEST(ProbeExperiment, DrawnSurfacesAndObject) {
  std::mt19937_64 rng(kTestSeed);
  std::uniform_real_distribution<double> mu(0.2, 1.2);
  const std::vector<SurfacePair> surfaces = {{"drawn-a", mu(rng)}, {"drawn-b", mu(rng)}};
  for (bool on_table : {false, true}) {
    ProbeConfig c;
    c.object = DrawObject(rng);
    c.on_table = on_table;
    c.force_sigma = 0;
    c.force_bias = 0;
    c.seed = rng();
    auto report = RunProbeExperiment(c, surfaces, 2);
    ASSERT_TRUE(report.ok()) << report.status();
    for (const ProbeTrialResult& t : report->trials) {
      SCOPED_TRACE(::testing::Message()
                   << t.surface << " mu " << t.mu_true << " table " << on_table);
      EXPECT_TRUE(t.valid) << t.invalid_reason;
      EXPECT_TRUE(t.slip_detected);
      EXPECT_TRUE(t.mesh_triangle == 2 || t.mesh_triangle == 3)
          << t.mesh_triangle;  // BoxMesh's top face
      EXPECT_LT(t.object_motion_mm, 1.0);
      EXPECT_NEAR(t.mu_estimated, t.mu_slope, 0.03);
      EXPECT_NEAR(t.mu_slope, t.mu_true, 0.02);
    }
    EXPECT_EQ(report->summary.valid, 4);
    EXPECT_EQ(report->summary.slip_detected_valid, 4);
  }
}

// The default tactile model (bias + noise per axis): each estimate within
// 0.01 + 4 standard deviations of what that model predicts for eq. 5 at the
// slip point, sd = sqrt(sigma^2 / window + bias^2) sqrt(1 + mu^2) / f_n,slip.
TEST(ProbeExperiment, NoisySensingStaysWithinItsPredictedSpread) {
  std::mt19937_64 rng(kTestSeed + 2);
  std::uniform_real_distribution<double> mu(0.2, 1.2);
  ProbeConfig c;
  c.seed = rng();
  const SurfacePair s{"drawn", mu(rng)};
  const double fn_slip = c.slope.probe_tangential / s.mu;
  const double sd = std::sqrt(c.force_sigma * c.force_sigma / c.slope.friction.window +
                              c.force_bias * c.force_bias) *
                    std::sqrt(1 + s.mu * s.mu) / fn_slip;
  auto report = RunProbeExperiment(c, {s}, 4);
  ASSERT_TRUE(report.ok()) << report.status();
  for (const ProbeTrialResult& t : report->trials) {
    EXPECT_TRUE(t.valid) << t.invalid_reason;
    EXPECT_NEAR(t.mu_estimated, t.mu_slope, 0.01 + 4 * sd) << "mu " << s.mu;
  }
}

// The negative control: a third of the holding force cannot keep the box
// still, so no trial is valid and no mu enters the summary.
TEST(ProbeExperiment, WeakHoldIsInvalid) {
  std::mt19937_64 rng(kTestSeed + 1);
  std::uniform_real_distribution<double> mu(0.3, 1.0);
  ProbeConfig c;
  c.hold_scale = 0.3;
  c.seed = rng();
  const SurfacePair s{"drawn", mu(rng)};
  auto report = RunProbeExperiment(c, {s}, 3);
  ASSERT_TRUE(report.ok()) << report.status();
  for (const ProbeTrialResult& t : report->trials) {
    EXPECT_FALSE(t.valid) << "mu " << s.mu << " estimate " << t.mu_estimated;
    EXPECT_FALSE(t.invalid_reason.empty());
    EXPECT_EQ(t.mu_estimated, 0);
  }
  EXPECT_EQ(report->summary.valid, 0);
  EXPECT_EQ(report->summary.per_surface[0].valid, 0);
}

// Same seed, same trial: the same draws and the same estimate.
TEST(ProbeExperiment, Deterministic) {
  ProbeConfig c;
  c.seed = kTestSeed;
  const SurfacePair s{"x", 0.7};
  auto a = RunProbeTrial(c, s, 3, 0.7);
  auto b = RunProbeTrial(c, s, 3, 0.7);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->mu_estimated, b->mu_estimated);
  EXPECT_EQ(a->object_motion_mm, b->object_motion_mm);
}

using ProbeCliTest = testing::CliTest;

TEST_F(ProbeCliTest, JsonHasTheIssueFields) {
  auto r = Tactforce(
      {"experiment", "probe", "--mu", "0.65", "--trials", "2", "--json", "--no-progress"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto doc = io::ParseJson(r.out, "stdout");
  ASSERT_TRUE(doc.ok()) << doc.status() << r.out;
  const io::JsonValue* trials = doc->Find("trials");
  ASSERT_TRUE(trials && trials->is_array() && trials->array().size() == 2u) << r.out;
  for (const char* f :
       {"surface", "mu_true", "mu_slope", "mu_estimated", "error", "valid", "invalid_reason",
        "object_motion_mm", "object_rotation_deg", "slip_detected"})
    EXPECT_NE(trials->array()[0].Find(f), nullptr) << f;
  const io::JsonValue* summary = doc->Find("summary");
  ASSERT_NE(summary, nullptr);
  for (const char* f :
       {"trials", "valid", "median_signed_error", "median_abs_error", "per_surface"})
    EXPECT_NE(summary->Find(f), nullptr) << f;
  EXPECT_EQ(summary->Find("trials")->number(), 2);
  EXPECT_EQ(trials->array()[0].Find("mu_true")->number(), 0.65);
}

TEST_F(ProbeCliTest, TableShowsThePapersMedian) {
  const auto obj = Write("o.json", R"({"size": [0.07, 0.05, 0.05], "mass": 0.12})");
  auto r = Tactforce({"experiment", "probe", "--mu", "0.9", "--trials", "1", "--object",
                      obj.string(), "--on-table"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("paper: 0.0056"), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("on a table"), std::string::npos) << r.out;
}

TEST_F(ProbeCliTest, BadInputExits2NamingTheFlag) {
  const auto neg = Write("neg.json", R"({"size": [0.07, 0.05, 0.05], "mass": -0.12})");
  const std::vector<testing::BadFlagCase> cases = {
      {{"--object", "banana"}, "--object"},
      {{"--object", neg.string()}, "mass"},
      {{"--object", (dir() / "missing.json").string()}, "missing.json"},
      {{"--mu", "0.5,3"}, "--mu"},
      {{"--mu", "0.05"}, "--mu"},
      {{"--hold-scale", "0"}, "--hold-scale"},
      {{"--force-sigma", "-1"}, "--force-sigma"},
      {{"--trials", "0"}, "--trials"},
      {{"--admittance-gain", "2"}, "--admittance-gain"},
      {{"--pre-slip", "guess"}, "--pre-slip"},
  };
  ExpectBadFlags({"experiment", "probe"}, cases);
}

}  // namespace
}  // namespace tactforce::experiment
