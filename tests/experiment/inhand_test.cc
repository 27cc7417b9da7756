// The in-hand inertia data source (experiment/inhand.h): the data source
// itself on an object drawn at test time, the kinematic tracker's drift after
// an injected slip, the force model's calibration, a scheduled contact
// break, determinism, and bad input through the CLI.
#include "tactforce/experiment/inhand.h"

#include <cmath>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>

#include "support/cli_fixture.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "support/test_seed.h"

namespace tactforce::experiment {
namespace {

// A box drawn from `seed`: edges 5-10 cm / 5-8 cm / 10-20 cm, 0.08-0.25 kg,
// one internal point mass of 10-40 % of the mass.
InHandObject DrawObject(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0, 1);
  InHandObject o;
  o.name = "drawn";
  o.dimensions = Eigen::Vector3d(0.10 + 0.10 * U(rng), 0.05 + 0.03 * U(rng), 0.05 + 0.05 * U(rng));
  o.mass = 0.08 + 0.17 * U(rng);
  o.center = Eigen::Vector3d(0.02 * U(rng), -0.01 * U(rng), 0.01 * U(rng));
  PointMass p;
  p.mass = (0.1 + 0.3 * U(rng)) * o.mass;
  for (int k = 0; k < 3; ++k) p.position(k) = o.center(k) + (U(rng) - 0.5) * 0.6 * o.dimensions(k);
  o.point_masses.push_back(p);
  return o;
}

uint64_t TestSeed() { return 20240601 + ::tactforce::testing::GtestSeed(); }

TEST(InHandTest, IdealDataSourceOnADrawnObject) {
  InHandConfig c;
  c.custom = DrawObject(TestSeed());
  c.duration = 6;
  c.ideal_forces = true;
  c.ideal_tracking = true;
  auto run = RunInHand(c);
  ASSERT_TRUE(run.ok()) << run.status();
  const InHandStats& st = run->stats;
  EXPECT_LE(st.ne_residual_force_max, 0.01 * st.mg);
  EXPECT_EQ(st.contact_losses, 0);
  EXPECT_GT(st.min_normal_force, 0.5);
  EXPECT_EQ(run->samples.samples.size(), 601u);
  auto fit = inertia::FitInertia(run->samples,
                                 InHandFitOptions(*run, inertia::InertiaMethod::kConstrained));
  ASSERT_TRUE(fit.ok()) << fit.status();
  const inertia::InertiaErrors e = inertia::CompareInertia(run->truth, fit->params);
  EXPECT_LE(e.mass_percent, 2.0);
  EXPECT_LE(e.riemannian, 0.05) << "mass " << run->truth.mass << " point mass "
                                << c.custom->point_masses[0].mass;
}

TEST(InHandTest, KinematicTrackerDriftsWithInjectedSlip) {
  InHandConfig c;
  c.object = "box_2";
  c.duration = 4;
  c.tracker = Tracker::kKinematic;
  c.ideal_forces = true;
  c.position_scale = 0;  // hold still: the drift is the slip alone
  c.orientation_scale = 0;
  Push push;
  push.start = 1.5;
  push.duration = 0.02;
  std::mt19937_64 rng(TestSeed());
  push.force = Eigen::Vector3d(0, std::uniform_real_distribution<double>(9, 11)(rng),
                               0);  // along the long edge
  c.pushes = {push};
  auto run = RunInHand(c);
  ASSERT_TRUE(run.ok()) << run.status();
  // Where the tracked and the true pose put the point fingertip 0 touched at
  // t0: the tracker keeps it under the fingertip, so they part by its slip.
  const Eigen::Vector3d c0 = run->truth_log[0].point[0];
  auto point_error_mm = [&](size_t k) {
    const inertia::InertiaSample& x = run->samples.samples[k];
    const InHandTruthRow& t = run->truth_log[k];
    return 1e3 * ((x.position + x.orientation * c0) - (t.position + t.orientation * c0)).norm();
  };
  const size_t before = 140, after = run->truth_log.size() - 1;  // t = 1.4 s and the end
  EXPECT_LT(point_error_mm(before), 0.3);
  EXPECT_LT(1e3 * run->tracker_error[before].norm(), 0.3);
  const double slip0 = run->truth_log[after].slip_mm[0];
  EXPECT_GT(slip0, 1.0) << "the push did not make the grasp slip";
  EXPECT_NEAR(point_error_mm(after), slip0, 0.2 * slip0 + 0.2);
  EXPECT_GT(1e3 * run->tracker_error[after].norm(), 0.5 * slip0);  // the origin drifts too
  EXPECT_GT(run->stats.slip_tracker_correlation, 0.9);
}

TEST(InHandTest, ForceModelSigmaIsCalibrated) {
  InHandConfig c;
  c.object = "box_1";
  c.duration = 6;
  c.seed = TestSeed();
  c.tracker = Tracker::kKinematic;
  auto run = RunInHand(c);
  ASSERT_TRUE(run.ok()) << run.status();
  EXPECT_GE(run->stats.sigma_coverage, 0.60);
  EXPECT_LE(run->stats.sigma_coverage, 0.76);
  EXPECT_GT(run->stats.median_magnitude_error, 0.01);
  for (const inertia::InertiaSample& x : run->samples.samples)
    for (const inertia::ContactReading& r : x.contacts) ASSERT_GT(r.sigma, 0.0);
}

TEST(InHandTest, ContactBreakLogsZeroForceAndTheFitCompletes) {
  InHandConfig c;
  c.object = "box_3";
  c.duration = 5;
  c.seed = TestSeed();
  ContactBreak b;
  b.contact = 2;
  b.start = 2.0;
  b.duration = 0.6;
  c.breaks = {b};
  auto run = RunInHand(c);
  ASSERT_TRUE(run.ok()) << run.status();
  int zero_rows = 0;
  for (size_t k = 0; k < run->samples.samples.size(); ++k) {
    const double t = run->samples.samples[k].t;
    const inertia::ContactReading& r = run->samples.samples[k].contacts[2];
    if (t > 2.1 && t < 2.55) {
      EXPECT_EQ(r.force, Eigen::Vector3d::Zero()) << "t = " << t;
      EXPECT_FALSE(run->truth_log[k].in_contact[2]);
      ++zero_rows;
    }
    if (t < 1.9 || t > 2.8) EXPECT_TRUE(run->truth_log[k].in_contact[2]) << "t = " << t;
  }
  EXPECT_GE(zero_rows, 40);
  EXPECT_EQ(run->stats.contact_losses, 0);  // the break is scheduled, nothing else let go
  for (auto method : {inertia::InertiaMethod::kConstrained, inertia::InertiaMethod::kBaselineLs}) {
    auto fit = inertia::FitInertia(run->samples, InHandFitOptions(*run, method));
    ASSERT_TRUE(fit.ok()) << fit.status();
    EXPECT_TRUE(std::isfinite(fit->params.mass));
  }
}

TEST(InHandTest, SameSeedSameLog) {
  InHandConfig c;
  c.duration = 1;
  c.seed = TestSeed();
  auto a = RunInHand(c), b = RunInHand(c);
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->samples.samples.size(), b->samples.samples.size());
  for (size_t k = 0; k < a->samples.samples.size(); ++k) {
    EXPECT_EQ(a->samples.samples[k].position, b->samples.samples[k].position);
    EXPECT_EQ(a->samples.samples[k].contacts[1].force, b->samples.samples[k].contacts[1].force);
  }
}

TEST(InHandTest, ConfigErrorsNameTheField) {
  InHandConfig c;
  c.rate = 0;
  EXPECT_NE(ValidateInHandConfig(c).message().find("rate"), std::string::npos);
  c = InHandConfig{};
  c.object = "box_9";
  EXPECT_NE(ValidateInHandConfig(c).message().find("object"), std::string::npos);
  auto o = ParseInHandObjectJson(R"({"dimensions": [0.1, 0.05, 0.06], "mass": -1})", "neg.json");
  ASSERT_FALSE(o.ok());
  EXPECT_NE(o.status().message().find("mass"), std::string::npos) << o.status();
  o = ParseInHandObjectJson(R"({"dimensions": [0.1, 0.05, 0.06], "mass": 0.2,
      "point_masses": [{"mass": 0.05, "position": [0.2, 0, 0]}]})",
                            "out.json");
  ASSERT_FALSE(o.ok());
  EXPECT_NE(o.status().message().find("point_masses[0].position"), std::string::npos) << o.status();
}

using InHandCliTest = testing::CliTest;

TEST_F(InHandCliTest, BadInputExitsTwoNamingTheFlagAndWritesNothing) {
  const std::string out = (dir() / "run").string();
  testing::CliRun r = Tactforce({"experiment", "inhand", "--object", "box_9", "--out", out});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--object"), std::string::npos) << r.err;
  const auto neg = Write("neg.json", R"({"dimensions": [0.1, 0.05, 0.06], "mass": -0.2})");
  r = Tactforce({"experiment", "inhand", "--object", neg.string(), "--out", out});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--object"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("mass"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "inhand", "--rate", "0", "--out", out});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--rate"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "inhand", "--break", "7:1:1", "--out", out});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--break"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(out));
}

TEST_F(InHandCliTest, WritesTheLogThatInertiaReads) {
  const std::string out = (dir() / "run").string();
  testing::CliRun r = Tactforce({"experiment", "inhand", "--duration", "2", "--tracker",
                                 "kinematic", "--out", out, "--json", "--no-progress"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_EQ(r.out.rfind("{\n  \"object\": \"box_0\",\n  \"samples\": 201,", 0), 0u) << r.out;
  for (const char* f : {"inertia.csv", "truth.json", "events.csv", "truth_log.csv", "mesh.obj"})
    EXPECT_TRUE(std::filesystem::exists(std::filesystem::path(out) / f)) << f;
  const std::string header =
      testing::Lines(testing::ReadFile(std::filesystem::path(out) / "inertia.csv"))[0];
  EXPECT_NE(header.find("c3_sigma"), std::string::npos) << header;
  r = Tactforce({"inertia", "--csv", out + "/inertia.csv", "--truth", out + "/truth.json", "--mesh",
                 out + "/mesh.obj", "--method", "density"});
  EXPECT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("errors against the truth"), std::string::npos) << r.out;
}

}  // namespace
}  // namespace tactforce::experiment
