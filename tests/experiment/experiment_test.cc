// Closed-loop grasp experiments and the slope method in MuJoCo.
#include <cmath>
#include <cstdio>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tactforce/experiment/grasp.h"
#include "tactforce/experiment/sensor_channel.h"
#include "tactforce/experiment/slope.h"
#include "tactforce/io/svg.h"
#include "tactforce/sim/sensor_model.h"

namespace tactforce::experiment {
namespace {

// Shorter phases than the CLI's defaults so the suite stays quick; same loop.
GraspConfig ShortConfig(GraspObject object) {
  GraspConfig c;
  c.object = object;
  c.phases = {0.25, 0.4, 0.3, 0.6, 0.6, 0.0};
  return c;
}

class IdealSensorTrial : public ::testing::TestWithParam<GraspObject> {};

// Ideal sensors: the estimated-force loop (the full admittance) and a
// raw loop that regulates only the sensed normals both hold every object.
TEST_P(IdealSensorTrial, Succeeds) {
  for (Feedback f : {Feedback::kRaw, Feedback::kEstimated}) {
    GraspConfig c = ShortConfig(GetParam());
    c.sensors = SensorMode::kIdeal;
    c.feedback = f;
    if (f == Feedback::kRaw) c.admittance = Admittance::kNormal;
    auto setup = GraspSetup::Create(c);
    ASSERT_TRUE(setup.ok()) << setup.status();
    auto r = RunGraspTrial(**setup, 0);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_TRUE(r->success) << ToString(GetParam()) << " " << ToString(f) << ": " << r->failure
                            << " slip " << r->max_slip * 1e3 << " mm rot " << r->max_rotation_deg
                            << " deg";
    EXPECT_LT(r->force_error, 0.15) << ToString(GetParam()) << " " << ToString(f);
    EXPECT_GE(r->converge_time, 0.0) << ToString(GetParam()) << " " << ToString(f);
    EXPECT_EQ(r->estimate_failures, 0);
  }
}

INSTANTIATE_TEST_SUITE_P(Objects, IdealSensorTrial,
                         ::testing::Values(GraspObject::kSphere, GraspObject::kWrench,
                                           GraspObject::kCylinder, GraspObject::kCube),
                         [](const auto& info) { return std::string(ToString(info.param)); });

// The object table: each object's fingers, where it rests on the table, its
// MJCF geoms and contact pairs (every fingertip with every object geom, every
// object geom with the table).
TEST(GraspSetup, EveryObjectBuildsItsFingersGeomsAndPairs) {
  struct Expected {
    GraspObject object;
    std::vector<std::string> fingers;
    std::string rest;  // object origin at rest (m)
    int geoms;
  };
  const Expected expected[] = {
      {GraspObject::kSphere, {"thumb", "index"}, "0 0 0.035", 1},
      {GraspObject::kWrench, {"index", "middle", "thumb"}, "0 0 0.008", 2},
      {GraspObject::kCylinder, {"thumb", "index", "middle", "ring"}, "0 0 0.06", 1},
      {GraspObject::kCube, {"thumb", "index"}, "0 0 0.04", 1}};
  auto count = [](const std::string& text, const std::string& what) {
    int n = 0;
    for (size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
  };
  ASSERT_EQ(std::size(expected), AllGraspObjects().size());
  for (const Expected& e : expected) {
    auto setup = GraspSetup::Create(ShortConfig(e.object));
    ASSERT_TRUE(setup.ok()) << ToString(e.object) << ": " << setup.status();
    EXPECT_EQ((*setup)->finger_names(), e.fingers) << ToString(e.object);
    const std::string& mjcf = (*setup)->mjcf();
    EXPECT_NE(mjcf.find("<body name=\"object\" pos=\"" + e.rest + "\">"), std::string::npos)
        << mjcf;
    EXPECT_EQ(count(mjcf, "<geom name=\"obj"), e.geoms) << ToString(e.object);
    EXPECT_EQ(count(mjcf, "<pair "), e.geoms * (static_cast<int>(e.fingers.size()) + 1))
        << ToString(e.object);
    EXPECT_EQ(count(mjcf, "<body name=\"f"), static_cast<int>(e.fingers.size()))
        << ToString(e.object);
  }
}

// The GeoDEx claim on a fixed seed set: with the default error model,
// feedback on the estimate succeeds strictly more often than on raw readings.
TEST(GraspExperiment, EstimatedBeatsRawWithDefaultErrors) {
  int raw = 0, estimated = 0, n = 0;
  for (GraspObject o : {GraspObject::kWrench, GraspObject::kCylinder}) {
    for (Feedback f : {Feedback::kRaw, Feedback::kEstimated}) {
      GraspConfig c = ShortConfig(o);
      c.feedback = f;
      c.seed = 7;
      auto b = RunGraspBatch(c, 4);
      ASSERT_TRUE(b.ok()) << b.status();
      (f == Feedback::kRaw ? raw : estimated) += b->successes;
      if (f == Feedback::kRaw) n += b->trials;
      std::printf("%s %s: %d/%d, force error %.3f +- %.3f N\n", ToString(o), ToString(f),
                  b->successes, b->trials, b->force_error_mean, b->force_error_std);
    }
  }
  EXPECT_GT(estimated, raw) << "estimated " << estimated << "/" << n << " vs raw " << raw << "/"
                            << n;
}

TEST(GraspExperiment, DeterministicForASeed) {
  GraspConfig c = ShortConfig(GraspObject::kSphere);
  c.seed = 3;
  auto s = GraspSetup::Create(c);
  ASSERT_TRUE(s.ok());
  auto a = RunGraspTrial(**s, 1), b = RunGraspTrial(**s, 1);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->force_error, b->force_error);
  EXPECT_EQ(a->max_slip, b->max_slip);
  ASSERT_EQ(a->sensor_models.size(), 2u);
  EXPECT_EQ(a->sensor_models[0].offset, b->sensor_models[0].offset);
  // Raw and estimated feedback see the same sensor draws (paired trials).
  c.feedback = Feedback::kRaw;
  auto s2 = GraspSetup::Create(c);
  auto r = RunGraspTrial(**s2, 1);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->sensor_models[0].offset, a->sensor_models[0].offset);
}

TEST(GraspExperiment, BadConfigsNameTheField) {
  auto expect_field = [](GraspConfig c, const std::string& field) {
    auto s = GraspSetup::Create(c);
    ASSERT_FALSE(s.ok()) << field;
    EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_EQ(s.status().message().substr(0, field.size()), field) << s.status().message();
  };
  GraspConfig c;
  c.phases.lift = 0;
  expect_field(c, "phases.lift");
  c = {};
  c.physics.timestep = -1;
  expect_field(c, "physics.timestep");
  c = {};
  c.physics.solref_timeconst = 0.001;
  expect_field(c, "physics.solref_timeconst");
  c = {};
  c.admittance_gain = 2;
  expect_field(c, "admittance_gain");
  c = {};
  c.error_ranges.threshold_max = 0.05;
  expect_field(c, "error_ranges.threshold_max");
  c = {};
  c.sensors = SensorMode::kModel;
  c.sensor_model.effects.threshold = -1;
  expect_field(c, "sensor_model.");
  c = {};
  c.control_rate = 5000;
  expect_field(c, "control_rate");
  c = {};
  c.fingertip_mass = 0.001;
  expect_field(c, "kp");
  EXPECT_FALSE(ParseGraspObject("banana").ok());
  EXPECT_EQ(std::string(ParseGraspObject("banana").status().message()).substr(0, 7), "object:");
  EXPECT_FALSE(RunGraspBatch(GraspConfig{}, 0).ok());
}

TEST(GraspExperiment, TracePlotIsSvg) {
  GraspConfig c = ShortConfig(GraspObject::kSphere);
  c.trace_trials = 1;
  auto s = GraspSetup::Create(c);
  ASSERT_TRUE(s.ok());
  auto r = RunGraspTrial(**s, 0);
  ASSERT_TRUE(r.ok());
  ASSERT_FALSE(r->trace.empty());
  const std::string svg = RenderSvg(TracePlot(*r, (*s)->finger_names(), "sphere"));
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("desired"), std::string::npos);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
}

// The streaming channel reproduces the sensor model's batch channel.
TEST(SensorChannel, MatchesApplyChannel) {
  sim::SensorModel m;
  m.effects.threshold = 0.3;
  m.effects.hysteresis_width = 0.3;
  m.effects.lag = 0.02;
  m.effects.curvature = 0.05;
  m.effects.saturation = 6;
  m.effects.drift = 0.01;
  m.effects.crosstalk = 0.1;
  std::vector<double> t, f, s;
  for (int i = 0; i < 2000; ++i) {
    t.push_back(i * 0.005);
    f.push_back(std::max(0.0, 3 * std::sin(0.7 * t.back()) + 1.5 * std::sin(2.3 * t.back())));
    s.push_back(0.3 * f.back());
  }
  const std::vector<double> batch = sim::PredictReading(m, t, f, s);
  auto ch = SensorChannel::Create(m, 1);
  ASSERT_TRUE(ch.ok());
  double worst = 0;
  for (size_t i = 0; i < t.size(); ++i)
    worst = std::max(worst, std::abs(ch->Step(t[i], f[i], s[i]) - batch[i]));
  EXPECT_LT(worst, 1e-9);
  // The other hysteresis form and the power law.
  m.effects.hysteresis_width = 0;
  m.effects.pi_thresholds = {0, 0.1, 0.3};
  m.effects.pi_weights = {1, 0.5, 0.25};
  m.effects.power_exponent = 0.8;
  const std::vector<double> batch2 = sim::PredictReading(m, t, f, s);
  auto ch2 = SensorChannel::Create(m, 1);
  ASSERT_TRUE(ch2.ok()) << ch2.status();
  worst = 0;
  for (size_t i = 0; i < t.size(); ++i)
    worst = std::max(worst, std::abs(ch2->Step(t[i], f[i], s[i]) - batch2[i]));
  EXPECT_LT(worst, 1e-9);
  sim::SensorModel bad;
  bad.noise = -1;
  EXPECT_FALSE(SensorChannel::Create(bad, 1).ok());
}

TEST(SensorChannel, GeoDexDrawsInRange) {
  std::mt19937_64 rng(5);
  for (int k = 0; k < 200; ++k) {
    const sim::SensorModel m = DrawGeoDexModel(ErrorRanges{}, rng);
    EXPECT_GE(m.effects.threshold, 0.1);
    EXPECT_LE(m.effects.threshold, 0.5);
    EXPECT_LE(m.effects.hysteresis_width, 0.4);
    EXPECT_GE(std::abs(m.offset), 0.1);
    EXPECT_LE(std::abs(m.offset), 0.5);
    EXPECT_GE(m.noise, 0.01);
    EXPECT_LE(m.noise, 0.03);
  }
}

TEST(Slope, RecoversMjcfFriction) {
  SlopeConfig c;
  for (double mu : {0.4, 0.8}) {
    auto r = RunSlopeAndProbe(c, mu);
    ASSERT_TRUE(r.ok()) << r.status();
    std::printf("mu %.2f: slope %.4f (tilt %.2f deg), probe %.4f%s\n", mu, r->mu_slope,
                r->slip_tilt_deg, r->mu_probe, r->probe_valid ? "" : " (invalid)");
    EXPECT_NEAR(r->mu_slope, mu, 0.02);
    EXPECT_TRUE(r->probe_valid) << r->probe_message;
    EXPECT_NEAR(r->mu_probe, mu, 0.05);
  }
}

TEST(Slope, CreepIsSmallWithChosenSettings) {
  auto v = MeasureCreep(PhysicsSettings{}, 0.5, 0.9);
  ASSERT_TRUE(v.ok()) << v.status();
  std::printf("creep at 90 %% of the cone: %.3g mm/s\n", *v * 1e3);
  EXPECT_LT(std::abs(*v), 1e-4);  // < 0.1 mm/s
}

TEST(Slope, BadConfigsNameTheField) {
  SlopeConfig c;
  c.mus = {0.5, -1};
  auto r = RunSlopeTable(c);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().message().substr(0, 6), "mus[1]");
  c = {};
  c.tilt_rate_deg = 0;
  EXPECT_EQ(ValidateSlopeConfig(c).message().substr(0, 13), "tilt_rate_deg");
  EXPECT_FALSE(MeasureCreep(PhysicsSettings{}, 0.5, 1.5).ok());
}

}  // namespace
}  // namespace tactforce::experiment
