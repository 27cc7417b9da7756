// The audit's internal steps on hand-made data whose answers are known: the
// one median time step, the closed-form gain/offset of a channel, and each
// residual diagnostic (RMS split, force bins, loading vs unloading, Ljung-Box,
// cross-correlation lag, trend).
#include <cmath>
#include <random>
#include <vector>

#include "audit_internal.h"
#include "channel_evaluator.h"
#include "effect_space.h"
#include "gtest/gtest.h"
#include "hidden_effects.h"

namespace tactforce::audit::internal {
namespace {

constexpr double kPi = 3.14159265358979323846;

// n samples at dt of a smooth press-release-like reference (0..4 N), the
// reading equal to it (unit gain, no offset).
MeasuredData Smooth(int n, double dt = 0.01) {
  MeasuredData d;
  d.source = "test";
  for (int i = 0; i < n; ++i) {
    const double t = i * dt;
    d.t.push_back(t);
    d.reference.push_back(2 - 2 * std::cos(2 * kPi * 0.5 * t));
  }
  d.reading = d.reference;
  d.segment_starts = {0};
  return d;
}

TEST(MedianStep, SkipsTrialRestartsAndRepeatedTimes) {
  // Steps 0.02, -0.02 (a restart), 0, 0 (repeats), 0.03: the median of the
  // positive ones is 0.03 (of all five it would be 0).
  EXPECT_DOUBLE_EQ(MedianStep({0, 0.02, 0, 0, 0, 0.03}, 1.0), 0.03);
  EXPECT_DOUBLE_EQ(MedianStep({0, 0.5, 1.5, 2.0}, 1.0), 0.5);  // steps 0.5, 1, 0.5
  EXPECT_DOUBLE_EQ(MedianStep({0, 0.1, 0.4, 0.6}, 0), 0.2);    // steps 0.1, 0.3, 0.2
}

TEST(MedianStep, FallbackWhenNoStepIncreases) {
  EXPECT_EQ(MedianStep({}, 1.0), 1.0);
  EXPECT_EQ(MedianStep({3.0}, 0.0), 0.0);
  EXPECT_EQ(MedianStep({1.0, 1.0, 0.5}, 7.0), 7.0);
}

TEST(RunStats, ScaleWithTheRun) {
  MeasuredData d = Smooth(400, 0.005);
  const RunStats st = ComputeRunStats(d);
  EXPECT_NEAR(st.fmin, 0, 1e-12);
  EXPECT_NEAR(st.fmax, 4, 1e-3);
  EXPECT_DOUBLE_EQ(st.range, st.fmax - st.fmin);
  EXPECT_DOUBLE_EQ(st.duration, d.t.back());
  EXPECT_NEAR(st.dt, 0.005, 1e-15);
  EXPECT_FALSE(st.has_shear);
}

TEST(ChannelEvaluator, ClosedFormGainOffsetAndHeldOutRss) {
  MeasuredData d = Smooth(200);
  for (double& y : d.reading) y = 3 * y + 2;
  for (int i = 150; i < 200; ++i) d.reading[i] += 0.5;  // held-out block off by 0.5
  ChannelEvaluator eng(d, 150);
  EXPECT_EQ(eng.n_train(), 150);
  EXPECT_EQ(eng.n_heldout(), 50);
  const AffineFit fit = eng.Evaluate(sim::EffectParams{}, true);
  EXPECT_NEAR(fit.a, 3, 1e-9);
  EXPECT_NEAR(fit.b, 2, 1e-9);
  EXPECT_NEAR(fit.rss_train, 0, 1e-9);
  EXPECT_NEAR(fit.rss_heldout, 50 * 0.25, 1e-6);
  EXPECT_EQ(eng.Evaluate(sim::EffectParams{}, false).rss_heldout, 0);
}

// Ranges of a run (the blocked hold-out's blocks) see the channel in the
// state the whole run leads to: a lag and a hysteresis mid-run are not
// restarted at the range's start, so a reading made by the same channel over
// the whole run fits exactly on any range, training or held-out.
TEST(ChannelEvaluator, RangesCarryTheChannelStateFromTheRunStart) {
  std::mt19937_64 rng(testing::TestSeed() + 26);
  MeasuredData d = Smooth(600);
  sim::EffectParams p;
  p.lag = std::uniform_real_distribution<double>(0.02, 0.1)(rng);
  p.hysteresis_width = std::uniform_real_distribution<double>(0.1, 0.4)(rng);
  ChannelEvaluator whole(d, 600);
  const std::vector<double> g = whole.FullChannel(p);
  for (int i = 0; i < 600; ++i) d.reading[i] = 2 * g[i] - 1;
  const int first = 230 + static_cast<int>(rng() % 40), cut = first + 120,
            last = cut + 100;  // mid-press
  ChannelEvaluator forward(d, {{first, cut}}, {{cut, last}});
  ChannelEvaluator reversed(d, {{cut, last}}, {{first, cut}});
  for (ChannelEvaluator* eng : {&forward, &reversed}) {
    const AffineFit fit = eng->Evaluate(p, true);
    EXPECT_NEAR(fit.a, 2, 1e-9);
    EXPECT_NEAR(fit.b, -1, 1e-9);
    EXPECT_NEAR(fit.rss_train, 0, 1e-8);  // round-off of the closed form
    EXPECT_NEAR(fit.rss_heldout, 0, 1e-8);
  }
  EXPECT_EQ(forward.n_train(), 120);
  EXPECT_EQ(reversed.n_heldout(), 120);
  const std::vector<double>& train = reversed.TrainChannel(p);
  ASSERT_EQ(train.size(), 100u);
  for (int i = 0; i < 100; ++i) EXPECT_DOUBLE_EQ(train[i], g[cut + i]);
  EXPECT_EQ(reversed.reading().front(), d.reading[cut]);
  // The same range cut out as a segment of its own restarts the lag and
  // the hysteresis: the fit is no longer exact (what the blocks did before).
  MeasuredData cutout;
  cutout.source = "cut";
  cutout.segment_starts = {0};
  for (int i = first; i < last; ++i) {
    cutout.t.push_back(d.t[i]);
    cutout.reference.push_back(d.reference[i]);
    cutout.reading.push_back(d.reading[i]);
  }
  ChannelEvaluator restarted(cutout, last - first);
  EXPECT_GT(restarted.Evaluate(p, false).rss_train, 1e-4);
}

TEST(Diagnostics, ResidualRmsSplitsTrainingAndHeldOut) {
  MeasuredData d = Smooth(100);
  std::vector<double> pred = d.reading;
  for (int i = 0; i < 100; ++i) d.reading[i] += i < 60 ? (i % 2 ? 1 : -1) : (i % 2 ? 2 : -2);
  const Diagnostics dg = Diagnose(d, pred, 2.0, 60, 0.1);
  EXPECT_NEAR(dg.train_rms, 1, 1e-12);
  EXPECT_NEAR(dg.heldout_rms, 2, 1e-12);
  EXPECT_NEAR(dg.heldout_rms_force, 1, 1e-12);  // divided by the gain
}

TEST(Diagnostics, BiasInTheUpperForceBinsOnly) {
  MeasuredData d = Smooth(400);
  std::vector<double> pred = d.reading;
  for (int i = 0; i < 400; ++i)
    if (d.reference[i] > 3.5) d.reading[i] += 0.2;  // the top eighth of 0..4 N
  const Diagnostics dg = Diagnose(d, pred, 1.0, 300, 0.1);
  ASSERT_EQ(dg.bias_bins.size(), 8u);
  for (int b = 0; b < 7; ++b) EXPECT_NEAR(dg.bias_bins[b].mean_residual, 0, 1e-12) << "bin " << b;
  EXPECT_NEAR(dg.bias_bins[7].mean_residual, 0.2, 0.03);
  EXPECT_GT(dg.bias_bins[7].count, 0);
}

TEST(Diagnostics, PlayHysteresisReadsLowWhileLoadingHighWhileUnloading) {
  MeasuredData d = Smooth(1000);
  sim::EffectParams play;
  play.hysteresis_width = 0.4;
  sim::ChannelInput in;
  in.t = d.t.data();
  in.force = d.reference.data();
  in.n = static_cast<int>(d.t.size());
  sim::ApplyChannel(play, in, &d.reading);
  const Diagnostics dg = Diagnose(d, d.reference, 1.0, 700, 0.1);
  EXPECT_GT(dg.loading_count, 100);
  EXPECT_GT(dg.unloading_count, 100);
  EXPECT_LT(dg.loading_mean, -0.1);   // the play operator lags the rise by up to width/2
  EXPECT_GT(dg.unloading_mean, 0.1);  // and the fall
}

TEST(Diagnostics, CrossCorrelationFindsTheReadingsDelay) {
  MeasuredData d = Smooth(600);
  const int shift = 7;
  for (int i = 0; i < 600; ++i)
    d.reading[i] = -5 * d.reference[std::max(0, i - shift)];  // negative gain
  const Diagnostics dg = Diagnose(d, d.reading, -5.0, 400, 0.2);
  EXPECT_EQ(dg.xcorr_lag_samples, shift);
  EXPECT_NEAR(dg.xcorr_lag_seconds, shift * 0.01, 1e-12);
}

TEST(Diagnostics, DriftShowsAsTrendAndRisingTimeBins) {
  MeasuredData d = Smooth(500);
  std::vector<double> pred = d.reading;
  for (int i = 0; i < 500; ++i) d.reading[i] += 0.1 * d.t[i];
  const Diagnostics dg = Diagnose(d, pred, 1.0, 300, 0.1);
  EXPECT_NEAR(dg.residual_time_slope, 0.1, 1e-9);
  ASSERT_EQ(dg.residual_time_bins.size(), 10u);
  for (int b = 1; b < 10; ++b) EXPECT_GT(dg.residual_time_bins[b], dg.residual_time_bins[b - 1]);
}

TEST(Diagnostics, LjungBoxTellsWhiteFromCorrelatedResiduals) {
  MeasuredData d = Smooth(2000);
  std::mt19937_64 rng(3);
  std::normal_distribution<double> gauss(0, 0.01);
  std::vector<double> white(2000), ar(2000);
  double e = 0;
  for (int i = 0; i < 2000; ++i) {
    white[i] = gauss(rng);
    e = 0.9 * e + gauss(rng);
    ar[i] = e;
  }
  std::vector<double> pred_white = d.reading, pred_ar = d.reading;
  for (int i = 0; i < 2000; ++i) {
    pred_white[i] -= white[i];
    pred_ar[i] -= ar[i];
  }
  const Diagnostics w = Diagnose(d, pred_white, 1.0, 1300, 0.1);
  const Diagnostics c = Diagnose(d, pred_ar, 1.0, 1300, 0.1);
  EXPECT_EQ(w.ljung_box_lags, 20);
  EXPECT_GT(w.ljung_box_p, 0.001);
  EXPECT_LT(c.ljung_box_p, 1e-9);
  EXPECT_GT(c.ljung_box_q, 10 * w.ljung_box_q);
}

TEST(EffectSpace, BicCountsPiOperatorsAndWeightsNormalise) {
  sim::EffectParams p;
  p.pi_thresholds = {0, 0.1, 0.2};
  p.pi_weights = {1, 2, 1};
  EXPECT_EQ(NumParams(Effect::kHysteresis, p), 3);
  EXPECT_EQ(NumParams(Effect::kDeadzone, p), 2);
  EXPECT_EQ(NumParams(Effect::kLag, p), 1);
  NormaliseWeights(&p.pi_weights);
  EXPECT_DOUBLE_EQ(p.pi_weights[1], 0.5);
  std::vector<double> zero = {0, 0};
  NormaliseWeights(&zero);
  EXPECT_EQ(zero[0], 0);
  EXPECT_DOUBLE_EQ(Bic(4.0, 4, 2), 2 * std::log(4.0));  // 4 ln(1) + 2 ln(4)
}

}  // namespace
}  // namespace tactforce::audit::internal
