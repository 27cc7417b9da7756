// Issue 26 in CI size: per-taxel CSVs (format, errors naming the column),
// partial_activation and phantom hidden in data generated here, late-only
// effects found by the blocked hold-out. Cases are drawn from a seed chosen
// at test time (printed; TACTFORCE_TEST_SEED=<n> repeats a run); the
// 200-seed evaluations are audit_hidden_eval (README).
#include <cstdlib>
#include <algorithm>
#include <iostream>
#include <random>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "hidden_effects.h"

namespace tactforce::audit {
namespace {

using ::testing::HasSubstr;

using testing::TestSeed;

AuditOptions Fast() {
  AuditOptions o;
  o.downstream_gain = false;
  o.uncertainties = false;
  return o;
}

std::string Message(const absl::Status& s) { return std::string(s.message()); }

// ---- the per-taxel CSV -----------------------------------------------------

std::string TaxelCsv(const std::vector<std::string>& taxel_columns, int rows) {
  std::string csv = "t,reference";
  for (const auto& c : taxel_columns) csv += "," + c;
  csv += "\n";
  for (int i = 0; i < rows; ++i) {
    const double f = 4 * std::sin(0.1 * i) * std::sin(0.1 * i);
    csv += std::to_string(0.01 * i) + "," + std::to_string(f);
    for (size_t j = 0; j < taxel_columns.size(); ++j)
      csv += "," + std::to_string(f * (j + 1) / 10.0);
    csv += "\n";
  }
  return csv;
}

TEST(TaxelCsv, ReadingIsTheSumOfTheTaxels) {
  auto d = ParseMeasuredCsv(TaxelCsv({"taxel_0", "taxel_1", "taxel_2"}, 60), "taxels.csv");
  ASSERT_TRUE(d.ok()) << d.status();
  ASSERT_EQ(d->taxels.size(), 3u);
  for (size_t i = 0; i < d->t.size(); ++i)
    EXPECT_NEAR(d->reading[i], d->taxels[0][i] + d->taxels[1][i] + d->taxels[2][i], 1e-9);
}

TEST(TaxelCsv, MissingColumnsAreNamed) {
  auto gap = ParseMeasuredCsv(TaxelCsv({"taxel_0", "taxel_2", "taxel_4"}, 60), "gap.csv");
  ASSERT_FALSE(gap.ok());
  EXPECT_THAT(Message(gap.status()), HasSubstr("gap.csv: missing column(s) taxel_1, taxel_3"));
  // 42 expected, 41 given: the last is named.
  std::vector<std::string> cols;
  for (int j = 0; j < 41; ++j) cols.push_back("taxel_" + std::to_string(j));
  auto short_of = ParseMeasuredCsv(TaxelCsv(cols, 60), "short.csv", 42);
  ASSERT_FALSE(short_of.ok());
  EXPECT_THAT(Message(short_of.status()), HasSubstr("missing column(s) taxel_41"));
  auto beyond = ParseMeasuredCsv(TaxelCsv(cols, 60), "beyond.csv", 8);
  ASSERT_FALSE(beyond.ok());
  EXPECT_THAT(Message(beyond.status()),
              HasSubstr("column 'taxel_40' beyond the 8 taxels expected"));
  auto none = ParseMeasuredCsv("t,reference,taxel\n0,1,2\n", "none.csv");
  ASSERT_FALSE(none.ok());
  EXPECT_THAT(Message(none.status()), HasSubstr("missing column(s) reading"));
}

TEST(TaxelCsv, NonNumberInATaxelColumnIsNamed) {
  std::string csv = TaxelCsv({"taxel_0", "taxel_1"}, 60);
  csv.replace(csv.rfind(',') + 1, std::string::npos, "1e300\n");
  auto d = ParseMeasuredCsv(csv, "big.csv");
  ASSERT_FALSE(d.ok());
  EXPECT_THAT(Message(d.status()), HasSubstr("column 'taxel_1'"));
}

TEST(Options, BlocksAndSilentSigmasAreChecked) {
  auto hc = testing::MakeHiddenCase({}, 5);
  AuditOptions o = Fast();
  o.blocks = 11;
  EXPECT_THAT(Message(RunAudit(hc.data, o).status()), HasSubstr("blocks"));
  o = Fast();
  o.silent_sigmas = 0;
  EXPECT_THAT(Message(RunAudit(hc.data, o).status()), HasSubstr("silent_sigmas"));
}

// ---- partial activation ----------------------------------------------------

TEST(PartialActivation, NamedFirstWithTheFraction) {
  std::mt19937_64 rng(TestSeed());
  for (int k = 0; k < 3; ++k) {
    const uint64_t seed = rng() % 1000000;
    const int dead = 1 + static_cast<int>(rng() % 8);
    auto tc = testing::MakeTaxelCase(seed, dead);
    auto rep = RunAudit(tc.data, Fast());
    ASSERT_TRUE(rep.ok()) << rep.status();
    ASSERT_FALSE(rep->causes.empty()) << "seed " << seed;
    EXPECT_EQ(rep->causes[0].effect, kPartialActivation) << "seed " << seed;
    EXPECT_NEAR(rep->causes[0].parameters.at("silent_taxels"), dead, 1) << "seed " << seed;
    EXPECT_NEAR(rep->causes[0].parameters.at("fraction"), dead / 42.0, 1 / 42.0) << "seed " << seed;
  }
}

TEST(PartialActivation, NotNamedWhenEveryTaxelActivates) {
  std::mt19937_64 rng(TestSeed() + 1);
  for (int k = 0; k < 2; ++k) {
    const uint64_t seed = rng() % 1000000;
    auto rep = RunAudit(testing::MakeTaxelCase(seed, 0).data, Fast());
    ASSERT_TRUE(rep.ok()) << rep.status();
    for (const auto& c : rep->causes) EXPECT_NE(c.effect, kPartialActivation) << "seed " << seed;
  }
}

// ---- phantom -----------------------------------------------------------------

TEST(Phantom, NamedFirstWithItsForce) {
  std::mt19937_64 rng(TestSeed() + 2);
  for (int k = 0; k < 3; ++k) {
    const uint64_t seed = rng() % 1000000;
    auto pc = testing::MakePhantomCase(seed);
    auto rep = RunAudit(pc.hc.data, testing::FastOptions(pc.hc));
    ASSERT_TRUE(rep.ok()) << rep.status();
    ASSERT_FALSE(rep->causes.empty()) << "seed " << seed;
    EXPECT_EQ(rep->causes[0].effect, kPhantom) << "seed " << seed;
    EXPECT_NEAR(rep->causes[0].parameters.at("phantom_force"), pc.force, 0.05 + 0.2 * pc.force)
        << "seed " << seed;
  }
}

TEST(Phantom, HysteresisIsNotAPhantom) {
  std::mt19937_64 rng(TestSeed() + 3);
  for (int k = 0; k < 2; ++k) {
    const uint64_t seed = rng() % 1000000;
    auto hc = testing::MakeHiddenCase({Effect::kHysteresis}, seed);
    auto rep = RunAudit(hc.data, testing::FastOptions(hc));
    ASSERT_TRUE(rep.ok()) << rep.status();
    ASSERT_FALSE(rep->causes.empty()) << "seed " << seed;
    EXPECT_EQ(rep->causes[0].effect, "hysteresis") << "seed " << seed;
    for (const auto& c : rep->causes) EXPECT_NE(c.effect, kPhantom) << "seed " << seed;
  }
}

// ---- blocked hold-out --------------------------------------------------------

// Late effects are named in ~95 % of the 200-seed evaluation (a late lag can
// be named delay), and a named one shows in the last block but not the first
// in most cases: 9 of 12 drawn cases must be both. A fixed 12 keeps a
// chance failure rare for any drawn seed (measured: 0 of 200 seeds below 9).
TEST(BlockedHoldout, LateEffectIsNamedAndItsBlockShown) {
  std::mt19937_64 rng(TestSeed() + 4);
  const std::vector<Effect> late = {Effect::kHysteresis, Effect::kLag, Effect::kNonlinearity,
                                    Effect::kDelay};
  int right = 0;
  for (int k = 0; k < 12; ++k) {
    const uint64_t seed = rng() % 1000000;
    const Effect e = late[(seed + k) % late.size()];
    auto hc = testing::MakeLateCase(e, seed);
    auto rep = RunAudit(hc.data, testing::FastOptions(hc));
    ASSERT_TRUE(rep.ok()) << rep.status();
    ASSERT_EQ(rep->block_times.size(), 5u);
    const Cause* found = nullptr;
    for (const auto& c : rep->causes)
      if (c.effect == EffectName(e)) found = &c;
    const auto has = [&](int b) {
      return std::find(found->blocks.begin(), found->blocks.end(), b) != found->blocks.end();
    };
    if (found != nullptr && has(4) && !has(1)) {
      ++right;
      continue;
    }
    std::cout << (found == nullptr ? "not named: " : "blocks wrong: ") << EffectName(e) << " seed "
              << seed << ":\n"
              << FormatAuditSummary(*rep);
  }
  EXPECT_GE(right, 9);
}

TEST(BlockedHoldout, StationaryEffectShowsInEveryBlock) {
  std::mt19937_64 rng(TestSeed() + 5);
  const uint64_t seed = rng() % 1000000;
  auto hc = testing::MakeHiddenCase({Effect::kHysteresis}, seed);
  auto rep = RunAudit(hc.data, testing::FastOptions(hc));
  ASSERT_TRUE(rep.ok()) << rep.status();
  ASSERT_FALSE(rep->causes.empty());
  EXPECT_EQ(rep->causes[0].found_by, "final_block");
  EXPECT_EQ(rep->causes[0].blocks, (std::vector<int>{1, 2, 3, 4})) << "seed " << seed;
}

}  // namespace
}  // namespace tactforce::audit
