// The streaming 42-taxel array (sim/taxel_array.h): per-taxel draws in their
// ranges, discrete activation jumps, the release residual, the fingertip
// error under partial contact, and errors that name the field.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "tactforce/sim/taxel_array.h"
#include "support/test_seed.h"

namespace tactforce::sim {
namespace {

// The draws follow GoogleTest's seed, printed once (support/test_seed.h).
uint64_t TestSeed() { return 20261127 + ::tactforce::testing::GtestSeed(); }

const Eigen::Vector3d kApex(0, 0, 0.042);  // DefaultFingertip's apex

TEST(TaxelArray, DrawsEveryTaxelInItsRanges) {
  TaxelRanges r;
  auto a = TaxelArray::Create(r, TestSeed());
  ASSERT_TRUE(a.ok()) << a.status();
  ASSERT_EQ(a->params().size(), 42u);
  std::set<double> thresholds;
  for (const TaxelParams& p : a->params()) {
    EXPECT_GE(p.threshold, r.threshold_min);
    EXPECT_LE(p.threshold, r.threshold_max);
    EXPECT_GE(p.hysteresis, 0);
    EXPECT_LE(p.hysteresis, r.hysteresis_max);
    EXPECT_GE(std::abs(p.force_error), r.force_error_min);
    EXPECT_LE(std::abs(p.force_error), r.force_error_max);
    EXPECT_GE(p.noise, r.noise_min);
    EXPECT_LE(p.noise, r.noise_max);
    thresholds.insert(p.threshold);
  }
  EXPECT_EQ(thresholds.size(), 42u) << "one draw per taxel, not one characterisation for all";
}

TEST(TaxelArray, LoadsArePressureShareTimesCosine) {
  const std::vector<Taxel> taxels = DefaultFingertip();
  const Eigen::Vector3d force(0.6, 0, -3.0);  // pressing into the apex, tilted
  const TaxelLoads l = ComputeTaxelLoads(taxels, TaxelRanges{}, kApex, force);
  double sum = 0;
  int loaded = 0;
  for (size_t i = 0; i < taxels.size(); ++i) {
    const double cosine = std::max(0.0, -force.dot(taxels[i].normal) / force.norm());
    EXPECT_LE(l.load[i], force.norm() * cosine + 1e-12);
    sum += l.load[i];
    loaded += l.load[i] > 0;
  }
  EXPECT_GT(loaded, 1) << "a patch, not a point";
  EXPECT_LT(sum, force.norm());
  EXPECT_GT(sum, 0.8 * force.norm());
  // The patch grows with the force.
  EXPECT_GT(ComputeTaxelLoads(taxels, TaxelRanges{}, kApex, 8 * force).patch_radius,
            l.patch_radius);
}

// Each taxel senses the pressure on its own part of the surface, so at a fixed
// contact no taxel's load falls while the force grows (the patch spreads, but
// the pressure under every point rises), and the loads add up to the force
// pressing along the taxels' normals. Contacts drawn from the test's seed.
TEST(TaxelArray, NoTaxelLoadFallsAsTheForceGrows) {
  const std::vector<Taxel> taxels = DefaultFingertip();
  const FingertipGeometry g;
  std::mt19937_64 rng(TestSeed() + 3);
  std::uniform_real_distribution<double> u(0, 1);
  for (int rep = 0; rep < 20; ++rep) {
    const double polar = 1.0 * u(rng), az = 2 * M_PI * u(rng);
    const Eigen::Vector3d n_out(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                                std::cos(polar));
    const Eigen::Vector3d contact = Eigen::Vector3d(0, 0, g.body_length) + g.radius * n_out;
    std::vector<double> prev(taxels.size(), 0.0);
    for (int k = 1; k <= 80; ++k) {
      const double f = 0.1 * k;
      const TaxelLoads l = ComputeTaxelLoads(taxels, TaxelRanges{}, contact, -f * n_out);
      double sum = 0;
      for (size_t i = 0; i < taxels.size(); ++i) {
        EXPECT_GE(l.load[i], prev[i] - 1e-9)
            << "rep " << rep << " taxel " << i << " at " << f << " N";
        prev[i] = l.load[i];
        sum += l.load[i];
      }
      EXPECT_LE(sum, f + 1e-9);
      EXPECT_GT(sum, 0.85 * f) << "rep " << rep << " at " << f
                               << " N: the patch's force is on the taxels";
    }
  }
}

// The dome's resolution is the covering radius of its taxels: every point of
// the hemisphere (directions drawn from the test's seed) lies within it of
// some taxel, seen from the tip's centre.
TEST(TaxelArray, DomeResolutionCoversTheHemisphere) {
  const FingertipGeometry g;
  const std::vector<Taxel> taxels = DefaultFingertip(g);
  const double res = DomeResolutionDeg(taxels, g);
  EXPECT_GT(res, 0.0);
  EXPECT_LT(res, 45.0);
  const Eigen::Vector3d centre(0, 0, g.body_length);
  std::mt19937_64 rng(TestSeed() + 4);
  std::uniform_real_distribution<double> u(0, 1);
  double worst = 0;
  for (int rep = 0; rep < 2000; ++rep) {
    const double c = u(rng), s = std::sqrt(1 - c * c), az = 2 * M_PI * u(rng);
    const Eigen::Vector3d dir(s * std::cos(az), s * std::sin(az), c);
    double best = 180;
    for (const Taxel& t : taxels)
      best = std::min(
          best, std::acos(std::clamp(dir.dot((t.position - centre).normalized()), -1.0, 1.0)) *
                    180 / M_PI);
    worst = std::max(worst, best);
  }
  EXPECT_LE(worst, res + 0.5) << "the 0.5 deg grid bounds the covering radius";
  EXPECT_GT(worst, 0.8 * res) << "2000 directions come near the worst point";
}

// Contacts off the apex (polar angle drawn up to 50 deg from the test's seed,
// 1-3 N along the surface normal, the paper's ranges): the sensed normal (the
// normalised force-weighted mean of the taxel normals) is off by up to the
// dome's resolution, and projecting the sensed location onto the surface puts
// it on the surface with that same normal (on the dome both are the mean
// direction of the loaded taxels): the projection moves the location out to
// the surface but cannot correct the normal.
TEST(TaxelArray, SensedContactOffTheApexWithinTheDomeResolution) {
  const FingertipGeometry g;
  const Eigen::Vector3d centre(0, 0, g.body_length);
  const double res = DomeResolutionDeg(DefaultFingertip(g), g);
  std::mt19937_64 rng(TestSeed() + 5);
  std::uniform_real_distribution<double> u(0, 1);
  int within = 0, sensed = 0;
  double sum_err = 0;
  for (int rep = 0; rep < 60; ++rep) {
    auto a = TaxelArray::Create(TaxelRanges{}, rng());
    ASSERT_TRUE(a.ok()) << a.status();
    const double polar = 50 * M_PI / 180 * u(rng), az = 2 * M_PI * u(rng), f = 1 + 2 * u(rng);
    const Eigen::Vector3d n(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                            std::cos(polar));
    const Eigen::Vector3d contact = centre + g.radius * n;
    for (int k = 1; k <= 40; ++k) a->Step(0.005 * k, contact, -f * k / 40 * n);
    const FingertipReading& r = a->last().fingertip;
    if (!(r.normal.norm() > 0.5)) continue;
    ++sensed;
    const double err = std::acos(std::clamp(r.normal.dot(n), -1.0, 1.0)) * 180 / M_PI;
    sum_err += err;
    within += err <= res;
    const Taxel p = ProjectOntoFingertip(g, r.location);
    EXPECT_NEAR((p.position - centre).norm(), g.radius, 1e-12);
    EXPECT_LT((p.normal - r.normal).norm(), 1e-9) << "rep " << rep;
  }
  std::printf("dome resolution %.2f deg; sensed %d/60, normal error mean %.2f deg, %d within\n",
              res, sensed, sum_err / std::max(1, sensed), within);
  EXPECT_GE(sensed, 55);
  EXPECT_GE(within, sensed - 3);
  EXPECT_LT(sum_err / std::max(1, sensed), res / 2);
}

// A slow press at the apex, noise off: every step where the summed reading
// jumps is a step where taxels cross their thresholds, one jump per crossing.
TEST(TaxelArray, PressGivesOneJumpPerTaxelCrossingThreshold) {
  TaxelRanges r;
  r.noise_min = r.noise_max = 0;
  std::mt19937_64 rng(TestSeed());
  for (int rep = 0; rep < 5; ++rep) {
    auto a = TaxelArray::Create(r, rng());
    ASSERT_TRUE(a.ok());
    const double tilt = std::uniform_real_distribution<double>(0, 0.3)(rng);
    const Eigen::Vector3d dir = Eigen::Vector3d(tilt, 0.1, -1).normalized();
    double prev = 0;
    int prev_active = 0, jumps = 0, visible_crossings = 0, crossings = 0;
    std::vector<double> prev_load(42, 0.0);
    const int steps = 20000;
    for (int k = 1; k <= steps; ++k) {
      const TaxelArrayReading& out = a->Step(k * 1e-4, kApex, (12.0 * k / steps) * dir);
      const double sum = out.fingertip.force;
      int new_active = 0;
      double jump_of_new = 0;
      for (size_t i = 0; i < out.reading.size(); ++i) {
        if (prev_load[i] < a->params()[i].threshold && out.load[i] >= a->params()[i].threshold)
          ++new_active, jump_of_new += out.reading[i];
        prev_load[i] = out.load[i];
      }
      crossings += new_active;
      if (new_active > 0 && jump_of_new > 0.05) ++visible_crossings;
      if (sum - prev > 0.05) ++jumps;
      prev = sum;
      prev_active = out.active;
    }
    EXPECT_GT(crossings, 3);
    EXPECT_EQ(jumps, visible_crossings) << "rep " << rep << ": " << crossings << " crossings";
    EXPECT_GE(prev_active, crossings - 1);
  }
}

// After a press and release every taxel reads at most its hysteresis (<= 0.2 N),
// and the residual relaxes away.
TEST(TaxelArray, ReleaseResidualIsAtMostTheHysteresis) {
  TaxelRanges r;
  r.noise_min = r.noise_max = 0;
  std::mt19937_64 rng(TestSeed() + 1);
  auto a = TaxelArray::Create(r, rng());
  ASSERT_TRUE(a.ok());
  const Eigen::Vector3d dir = Eigen::Vector3d(0.2, -0.1, -1).normalized();
  const int n = 400;
  for (int k = 0; k <= n; ++k) a->Step(k * 1e-3, kApex, 5.0 * std::sin(M_PI * k / n) * dir);
  const TaxelArrayReading& out = a->Step(0.402, kApex, Eigen::Vector3d::Zero());
  int residual = 0;
  for (size_t i = 0; i < out.reading.size(); ++i) {
    EXPECT_LE(out.reading[i], a->params()[i].hysteresis + 1e-12) << "taxel " << i;
    EXPECT_LE(out.reading[i], 0.2);
    residual += out.reading[i] > 0;
  }
  EXPECT_GT(residual, 0) << "hysteresis leaves a phantom reading after release";
  double later = 0;
  for (int k = 1; k <= 2000; ++k)
    later = a->Step(0.402 + k * 0.01, kApex, Eigen::Vector3d::Zero()).fingertip.force;
  EXPECT_EQ(later, 0);
}

// Partial contact (between taxels, on the tip's side, at an angle): the
// fingertip's summed force is off by 0.1-1 N on average (GeoDEx's per-taxel
// errors accumulated), location and normal point at the contact.
TEST(TaxelArray, PartialContactErrorWithinPaperRange) {
  std::mt19937_64 rng(TestSeed() + 2);
  std::uniform_real_distribution<double> u(0, 1);
  const FingertipGeometry g;
  double err_sum = 0;
  const int n = 60;
  for (int k = 0; k < n; ++k) {
    auto a = TaxelArray::Create(TaxelRanges{}, rng());
    ASSERT_TRUE(a.ok());
    const double polar = 0.2 + 0.8 * u(rng), az = 2 * M_PI * u(rng);
    const Eigen::Vector3d n_out(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                                std::cos(polar));
    const Eigen::Vector3d contact = Eigen::Vector3d(0, 0, g.body_length) + g.radius * n_out;
    const double f = 1 + 4 * u(rng);
    Eigen::Vector3d t = n_out.cross(Eigen::Vector3d::UnitZ());
    if (t.norm() < 1e-9) t = Eigen::Vector3d::UnitX();
    const Eigen::Vector3d force = f * (-n_out + 0.3 * u(rng) * t.normalized()).normalized();
    TaxelArrayReading out;
    for (int s = 0; s <= 100; ++s)
      out = a->Step(s * 0.005, contact, force * std::min(1.0, s / 50.0));
    err_sum += std::abs(out.fingertip.force - f);
    if (out.fingertip.force > 0.5) {
      EXPECT_LT((out.fingertip.location - contact).norm(), 0.006);
      EXPECT_GT(out.fingertip.normal.dot(n_out), 0.9);
    }
  }
  const double mean_err = err_sum / n;
  EXPECT_GE(mean_err, 0.1);
  EXPECT_LE(mean_err, 1.0);
  RecordProperty("mean_fingertip_error_N", std::to_string(mean_err));
}

TEST(TaxelRanges, BadValuesNameTheField) {
  TaxelRanges r;
  r.threshold_min = -0.1;
  EXPECT_NE(ValidateTaxelRanges(r, "taxels.").message().find("taxels.threshold_min"),
            std::string::npos);
  r = {};
  r.noise_max = 0.001;
  EXPECT_NE(ValidateTaxelRanges(r).message().find("noise_max"), std::string::npos);
  r = {};
  r.saturation = 0.3;
  EXPECT_NE(ValidateTaxelRanges(r).message().find("saturation"), std::string::npos);
  EXPECT_FALSE(TaxelArray::Create(r, 1).ok());

  auto j = TaxelRangesFromJson(
      "{\n \"format\": \"tactforce.taxel_ranges.v1\",\n \"threshold_min\": -0.2\n}", "m.json");
  ASSERT_FALSE(j.ok());
  EXPECT_NE(j.status().message().find("m.json:3"), std::string::npos) << j.status();
  EXPECT_NE(j.status().message().find("threshold_min"), std::string::npos);
  j = TaxelRangesFromJson("{\"treshold_min\": 0.2}", "m.json");
  ASSERT_FALSE(j.ok());
  EXPECT_NE(j.status().message().find("treshold_min"), std::string::npos);
  j = TaxelRangesFromJson("{\"threshold_min\": \"0.2\"}", "m.json");
  EXPECT_FALSE(j.ok());
}

TEST(TaxelRanges, JsonRoundTrip) {
  std::mt19937_64 rng(TestSeed() + 3);
  TaxelRanges r;
  r.threshold_min = 0.3 + 0.1 * std::uniform_real_distribution<double>(0, 1)(rng);
  r.threshold_max = r.threshold_min + 0.4;
  auto back = TaxelRangesFromJson(TaxelRangesToJson(r), "rt");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_NEAR(back->threshold_min, r.threshold_min, 1e-12);
  EXPECT_NEAR(back->threshold_max, r.threshold_max, 1e-12);
}

}  // namespace
}  // namespace tactforce::sim
