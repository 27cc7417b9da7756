// `experiment chain` (issue 28 item 3): the simulated-equivalent box, the
// config's errors, a chain run on an object drawn at test time, and the CLI's
// JSON contract and flag errors.
#include "tactforce/experiment/chain.h"

#include <cmath>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "support/cli_fixture.h"
#include "tactforce/io/json.h"

namespace tactforce::experiment {
namespace {

// The test's seed: CHAIN_SEED when set, else drawn now (printed for replay).
uint64_t TestSeed() {
  if (const char* s = std::getenv("CHAIN_SEED")) return std::strtoull(s, nullptr, 10);
  const uint64_t seed = std::random_device{}() % 1000 + 1;
  std::cout << "CHAIN_SEED=" << seed << "\n";
  return seed;
}

// A small chain: one seed, two trials, two probes, 2 s in hand.
ChainConfig SmallChain(GraspObject object, uint64_t seed) {
  ChainConfig c;
  c.objects = {object};
  c.seed = seed;
  c.seeds = 1;
  c.trials = 2;
  c.probe_trials = 2;
  c.inhand_duration = 2;
  return c;
}

TEST(ChainData, EquivalentBoxHasTheBoxesMoments) {
  std::mt19937_64 rng(TestSeed());
  std::uniform_real_distribution<double> edge(0.05, 0.25), mass(0.05, 1.0);
  for (int k = 0; k < 20; ++k) {
    const double m = mass(rng), x = edge(rng), y = edge(rng), z = edge(rng);
    const planner::Inertia I{
        m * (y * y + z * z) / 12, m * (x * x + z * z) / 12, m * (x * x + y * y) / 12, 0, 0, 0};
    const planner::Vec3 com(0.01, -0.005, 0.002);
    const InHandObject o = InHandEquivalent("box", m, com, I);
    EXPECT_NEAR(o.dimensions.x(), x, 1e-9);
    EXPECT_NEAR(o.dimensions.y(), y, 1e-9);
    EXPECT_NEAR(o.dimensions.z(), z, 1e-9);
    EXPECT_EQ(o.mass, m);
    EXPECT_TRUE(o.center.isApprox(com));
    EXPECT_TRUE(ValidateInHandObject(o).ok());
  }
}

TEST(ChainData, ConfigErrorsNameTheField) {
  const std::vector<std::pair<std::function<void(ChainConfig&)>, std::string>> cases = {
      {[](ChainConfig& c) { c.objects.clear(); }, "objects"},
      {[](ChainConfig& c) { c.trials = 0; }, "trials"},
      {[](ChainConfig& c) { c.seeds = 0; }, "seeds"},
      {[](ChainConfig& c) { c.probe_trials = 1; }, "probe_trials"},
      {[](ChainConfig& c) { c.inhand_duration = 0.5; }, "inhand_duration"},
      {[](ChainConfig& c) { c.confidence = -1; }, "confidence"},
      {[](ChainConfig& c) { c.confidence = std::nan(""); }, "confidence"},
  };
  for (const auto& [edit, field] : cases) {
    ChainConfig c;
    edit(c);
    const absl::Status s = ValidateChainConfig(c);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << field;
    EXPECT_EQ(std::string(s.message()).rfind(field, 0), 0u) << s;
  }
}

// Every row counts its trials and simulates them; the estimates carry their
// uncertainty and are near the truth.
TEST(Chain, DrawnObjectRowsAndEstimates) {
  const uint64_t seed = TestSeed();
  // Not the sphere: its 2-finger pinch has no plan for a CoM estimate off the pinch axis (README).
  const std::vector<GraspObject> objects = {GraspObject::kWrench, GraspObject::kCylinder,
                                            GraspObject::kCube};
  const GraspObject object = objects[seed % objects.size()];
  absl::StatusOr<ChainReport> r = RunChain(SmallChain(object, seed));
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_EQ(r->rows.size(), 3u);
  ASSERT_EQ(r->estimates.size(), 1u);
  const ChainEstimates& e = r->estimates[0];
  EXPECT_GT(e.mu_sigma, 0);
  EXPECT_GT(e.uncertain.uncertainty.covariance.norm(), 0);
  EXPECT_EQ(e.point.uncertainty.covariance.norm(), 0);
  EXPECT_NEAR(e.mu, e.mu_true, 0.15);
  EXPECT_NEAR(e.mass, e.mass_true, 0.3 * e.mass_true);
  for (int p = 0; p < 3; ++p) {
    EXPECT_EQ(r->rows[p].planning, static_cast<Planning>(p));
    EXPECT_EQ(r->rows[p].trials, 2);
    EXPECT_EQ(r->rows[p].trials_run, 2) << r->rows[p].plan_failure;
    EXPECT_LE(r->rows[p].successes, 2);
    EXPECT_GT(r->rows[p].median_squeeze_n, 0);
    EXPECT_LE(r->rows[p].min_slip_margin, 1);
  }
  // Not asserted: that the uncertain row squeezes at least as hard as the
  // point row. That is a measured tendency of the closed loop (README's chain
  // table, 50 trials a row), not a per-seed guarantee: with 2 trials, seed 169
  // (cylinder) gave 6.699 N uncertain vs 6.719 N point.
}

using ChainCliTest = testing::CliTest;

TEST_F(ChainCliTest, JsonHasTheContractFields) {
  auto r = Tactforce({"experiment", "chain", "--objects", "wrench", "--trials", "2", "--seeds", "1",
                      "--probe-trials", "2", "--inhand-duration", "2", "--json", "--no-progress"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  auto doc = io::ParseJson(r.out, "stdout");
  ASSERT_TRUE(doc.ok()) << doc.status() << r.out;
  const io::JsonValue* rows = doc->Find("rows");
  ASSERT_TRUE(rows && rows->is_array() && rows->array().size() == 3u) << r.out;
  const char* planning[] = {"truth", "point", "uncertain"};
  for (size_t i = 0; i < 3; ++i) {
    const io::JsonValue& row = rows->array()[i];
    for (const char* f :
         {"object", "planning", "successes", "trials", "median_squeeze_n", "min_slip_margin"})
      ASSERT_NE(row.Find(f), nullptr) << f;
    EXPECT_EQ(row.Find("object")->string(), "wrench");
    EXPECT_EQ(row.Find("planning")->string(), planning[i]);
    EXPECT_EQ(row.Find("trials")->number(), 2);
  }
  EXPECT_GE(rows->array()[2].Find("median_squeeze_n")->number(),
            rows->array()[1].Find("median_squeeze_n")->number());
}

TEST_F(ChainCliTest, BadInputExits2NamingTheFlag) {
  const std::vector<testing::BadFlagCase> cases = {
      {{"--objects", "banana"}, "--objects"},
      {{"--trials", "0"}, "--trials"},
      {{"--seeds", "0"}, "--seeds"},
      {{"--probe-trials", "1"}, "--probe-trials"},
      {{"--inhand-duration", "0"}, "--inhand-duration"},
      {{"--confidence", "-1"}, "--confidence"},
      {{"--fit-method", "guess"}, "--fit-method"},
  };
  ExpectBadFlags({"experiment", "chain", "--no-progress"}, cases);
}

}  // namespace
}  // namespace tactforce::experiment
