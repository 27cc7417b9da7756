// Tactile sensor simulation: fingertip geometry and aggregation, per-taxel
// effects, profiles, model JSON, writer.
#include <cmath>
#include <filesystem>
#include <fstream>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "tactforce/audit/measured_data.h"
#include "tactforce/sim/simulate.h"
#include "support/temp_dir.h"

namespace tactforce::sim {
namespace {

using ::testing::HasSubstr;

SimOptions Short(Profile p = Profile::kPressRelease) {
  SimOptions o;
  o.profile = p;
  o.seconds = 6;
  o.rate = 200;
  o.seed = 3;
  return o;
}

TEST(Fingertip, FortyTwoTaxelsWithUnitNormals) {
  FingertipGeometry g;
  auto taxels = DefaultFingertip(g);
  ASSERT_EQ(taxels.size(), 42u);
  EXPECT_NEAR((taxels[0].position - Eigen::Vector3d(0, 0, g.body_length + g.radius)).norm(), 0,
              1e-12);
  for (const auto& t : taxels) {
    EXPECT_NEAR(t.normal.norm(), 1, 1e-12);
    // On the surface: tip hemisphere or cylinder.
    if (t.position.z() > g.body_length + 1e-9)
      EXPECT_NEAR((t.position - Eigen::Vector3d(0, 0, g.body_length)).norm(), g.radius, 1e-12);
    else
      EXPECT_NEAR(std::hypot(t.position.x(), t.position.y()), g.radius, 1e-12);
  }
}

TEST(Fingertip, AggregationIsGeodexIVA) {
  auto taxels = DefaultFingertip();
  std::vector<double> r(42, 0.0);
  r[0] = 1.0;
  r[1] = 3.0;
  r[20] = -0.1;  // a negative reading counts in the sum, not in the weights
  auto f = AggregateFingertip(taxels, r);
  EXPECT_NEAR(f.force, 3.9, 1e-12);
  Eigen::Vector3d loc = (1.0 * taxels[0].position + 3.0 * taxels[1].position) / 4.0;
  Eigen::Vector3d nrm = (1.0 * taxels[0].normal + 3.0 * taxels[1].normal).normalized();
  EXPECT_NEAR((f.location - loc).norm(), 0, 1e-12);
  EXPECT_NEAR((f.normal - nrm).norm(), 0, 1e-12);
  auto none = AggregateFingertip(taxels, std::vector<double>(42, 0.0));
  EXPECT_EQ(none.force, 0);
  EXPECT_EQ(none.normal.norm(), 0);
}

TEST(Simulate, IdealModelReadsTheReference) {
  for (Profile p : {Profile::kPressRelease, Profile::kRamp, Profile::kRandom}) {
    auto run = SimulateSensor(SensorModel{}, Short(p));
    ASSERT_TRUE(run.ok()) << run.status();
    ASSERT_EQ(run->t.size(), 1200u);
    double fmax = 0;
    for (size_t i = 0; i < run->t.size(); ++i) {
      EXPECT_NEAR(run->reading[i], run->reference[i], 1e-9) << ToString(p) << " i=" << i;
      EXPECT_GE(run->reference[i], 0);
      fmax = std::max(fmax, run->reference[i]);
    }
    EXPECT_GT(fmax, 0.5) << ToString(p);
  }
}

TEST(Simulate, ContactSpreadOverTaxelsSumsToTheForce) {
  SimOptions o = Short();
  o.contact_taxel = 0;
  o.contact_radius = 0.008;
  auto run = SimulateSensor(SensorModel{}, o);
  ASSERT_TRUE(run.ok());
  auto taxels = DefaultFingertip();
  for (size_t i = 0; i < run->t.size(); ++i) {
    EXPECT_NEAR(run->fingertip[i].force, run->reference[i], 1e-9);
    if (run->reference[i] > 0.5) {
      // Symmetric patch around the apex: location on the axis, normal +z.
      EXPECT_NEAR(run->fingertip[i].location.x(), 0, 1e-9);
      EXPECT_NEAR(run->fingertip[i].normal.z(), 1, 1e-9);
      EXPECT_LT(run->fingertip[i].location.z(), taxels[0].position.z());
    }
  }
}

TEST(Simulate, GainOffsetAndEffects) {
  SensorModel m;
  m.gain = -40;
  m.offset = 1000;
  auto ideal = SimulateSensor(SensorModel{}, Short());
  auto run = SimulateSensor(m, Short());
  ASSERT_TRUE(run.ok());
  for (size_t i = 0; i < run->t.size(); ++i)
    EXPECT_NEAR(run->reading[i], 1000 - 40 * ideal->reading[i], 1e-9);

  SensorModel th;
  th.effects.threshold = 0.4;  // activation: jumps to the force at the threshold
  auto r = SimulateSensor(th, Short());
  for (size_t i = 0; i < r->t.size(); ++i) {
    if (r->reference[i] < 0.4)
      EXPECT_EQ(r->reading[i], 0);
    else
      EXPECT_NEAR(r->reading[i], r->reference[i], 1e-9);
  }

  SensorModel sat;
  sat.effects.saturation = 2.5;
  r = SimulateSensor(sat, Short());
  for (size_t i = 0; i < r->t.size(); ++i)
    EXPECT_NEAR(r->reading[i], std::min(2.5, r->reference[i]), 1e-9);

  SensorModel hy;
  hy.effects.hysteresis_width = 0.2;
  r = SimulateSensor(hy, Short());
  // After the first press, released rest periods read the residual width/2.
  bool pressed = false;
  int residual = 0;
  for (size_t i = 0; i < r->t.size(); ++i) {
    if (r->reference[i] > 1) pressed = true;
    if (pressed && r->reference[i] == 0) {
      EXPECT_NEAR(r->reading[i], 0.1, 1e-9);
      ++residual;
    }
  }
  EXPECT_GT(residual, 10);

  SensorModel de;
  de.effects.delay = 0.05;  // 10 samples at 200 Hz
  r = SimulateSensor(de, Short());
  for (size_t i = 10; i < r->t.size(); ++i) EXPECT_NEAR(r->reading[i], r->reference[i - 10], 1e-3);

  SensorModel dr;
  dr.effects.drift = 0.01;
  r = SimulateSensor(dr, Short());
  for (size_t i = 0; i < r->t.size(); ++i)
    EXPECT_NEAR(r->reading[i], r->reference[i] + 0.01 * r->t[i], 1e-9);

  SensorModel ct;
  ct.effects.crosstalk = 0.2;
  r = SimulateSensor(ct, Short());
  double smax = 0;
  for (size_t i = 0; i < r->t.size(); ++i) {
    EXPECT_NEAR(r->reading[i], r->reference[i] + 0.2 * r->shear[i], 1e-9);
    smax = std::max(smax, r->shear[i]);
  }
  EXPECT_GT(smax, 0.1);

  SensorModel lag;
  lag.effects.lag = 0.05;
  r = SimulateSensor(lag, Short());
  // The lagged reading stays between the extremes and trails a rising force.
  for (size_t i = 1; i < r->t.size(); ++i)
    if (r->reference[i] - r->reference[i - 1] > 0.02) {
      EXPECT_LT(r->reading[i], r->reference[i]);
    }
}

TEST(Simulate, NoiseIsSeededAndSized) {
  SensorModel m;
  m.noise = 0.02;
  auto a = SimulateSensor(m, Short());
  auto b = SimulateSensor(m, Short());
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(a->reading, b->reading);
  double s = 0;
  for (size_t i = 0; i < a->t.size(); ++i) s += std::pow(a->reading[i] - a->reference[i], 2);
  EXPECT_NEAR(std::sqrt(s / a->t.size()), 0.02, 0.003);
  SimOptions o = Short();
  o.seed = 4;
  auto c = SimulateSensor(m, o);
  EXPECT_NE(a->reading, c->reading);
}

TEST(Simulate, PartialContactError) {
  SensorModel m;
  m.partial_error = 0.3;
  SimOptions o = Short();
  o.contact_radius = 0.008;
  auto r = SimulateSensor(m, o);
  ASSERT_TRUE(r.ok());
  for (size_t i = 0; i < r->t.size(); ++i)
    if (r->reference[i] > 0.1) {
      EXPECT_GT(r->reading[i], r->reference[i] + 0.05);
    }
}

TEST(Simulate, BadOptionsNameTheField) {
  SimOptions o = Short();
  o.rate = -1;
  EXPECT_THAT(std::string(SimulateSensor(SensorModel{}, o).status().message()), HasSubstr("rate"));
  o = Short();
  o.contact_taxel = 42;
  EXPECT_THAT(std::string(SimulateSensor(SensorModel{}, o).status().message()),
              HasSubstr("contact_taxel"));
  SensorModel m;
  m.effects.threshold = -1;
  EXPECT_THAT(std::string(SimulateSensor(m, Short()).status().message()), HasSubstr("threshold"));
  EXPECT_FALSE(ParseProfile("sine").ok());
  EXPECT_EQ(*ParseProfile("ramp"), Profile::kRamp);
}

TEST(ModelJson, RoundTripAndErrors) {
  SensorModel m;
  m.units = "counts";
  m.gain = -37.5;
  m.offset = 1012.25;
  m.noise = 0.02;
  m.effects.threshold = 0.3;
  m.effects.delay = 0.02;
  m.effects.curvature = 0.031;
  m.uncertainty["threshold"] = 0.01;
  auto back = SensorModelFromJson(SensorModelToJson(m), "m.json");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->units, "counts");
  EXPECT_EQ(back->gain, m.gain);
  EXPECT_EQ(back->offset, m.offset);
  EXPECT_EQ(back->effects, m.effects);
  EXPECT_EQ(back->uncertainty, m.uncertainty);

  auto unknown = SensorModelFromJson("{\n  \"gain\": 1,\n  \"treshold\": 0.2\n}", "m.json");
  EXPECT_THAT(std::string(unknown.status().message()),
              HasSubstr("m.json:3: field 'treshold': unknown field; did you mean 'threshold'?"));
  auto bad = SensorModelFromJson("{\"lag\": \"fast\"}", "m.json");
  EXPECT_THAT(std::string(bad.status().message()), HasSubstr("field 'lag': expected a number"));
  auto range = SensorModelFromJson("{\"threshold_shift\": 2}", "m.json");
  EXPECT_THAT(std::string(range.status().message()), HasSubstr("threshold_shift"));
  auto syntax = SensorModelFromJson("{\"gain\" 1}", "m.json");
  EXPECT_THAT(std::string(syntax.status().message()), HasSubstr("m.json:1:9: expected ':'"));
  EXPECT_TRUE(SensorModelFromJson("{}", "m.json").ok());  // all off = ideal
}

// ---- Prandtl-Ishlinskii hysteresis and the power law ------------------------

TEST(ModelJson, PrandtlIshlinskiiAndPowerLawRoundTripAndErrors) {
  SensorModel m;
  m.effects.pi_thresholds = {0, 0.05, 0.2};
  m.effects.pi_weights = {0.3, 0.5, 0.2};
  m.effects.power_exponent = 0.8;
  m.uncertainty["pi_weights[1]"] = 0.01;
  m.uncertainty["power_exponent"] = 0.002;
  const std::string text = SensorModelToJson(m);
  EXPECT_THAT(text, HasSubstr("\"pi_thresholds\": [0, 0.05, 0.2]"));
  auto back = SensorModelFromJson(text, "m.json");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ(back->effects, m.effects);
  EXPECT_EQ(back->uncertainty, m.uncertainty);
  // Models without the new fields do not write them (older readers load them).
  EXPECT_THAT(SensorModelToJson(SensorModel{}), ::testing::Not(HasSubstr("pi_")));

  auto msg = [](const std::string& json) {
    return std::string(SensorModelFromJson(json, "m.json").status().message());
  };
  EXPECT_THAT(msg("{\"pi_thresholds\": [0, 0.1], \"pi_weights\": [1]}"), HasSubstr("same length"));
  EXPECT_THAT(msg("{\"pi_thresholds\": [0.1, 0.1], \"pi_weights\": [1, 1]}"),
              HasSubstr("'pi_thresholds[1]'"));
  EXPECT_THAT(msg("{\"pi_thresholds\": [0, 0.1], \"pi_weights\": [1, -1]}"),
              HasSubstr("'pi_weights[1]'"));
  EXPECT_THAT(msg("{\"pi_thresholds\": [0.1], \"pi_weights\": [0]}"),
              HasSubstr("must not all be 0"));
  EXPECT_THAT(msg("{\"pi_thresholds\": [0.1], \"pi_weights\": [1], \"hysteresis_width\": 0.1}"),
              HasSubstr("exclusive"));
  EXPECT_THAT(msg("{\"pi_thresholds\": 0.1, \"pi_weights\": [1]}"), HasSubstr("expected an array"));
  EXPECT_THAT(msg("{\"pi_thresholds\": [\"a\"], \"pi_weights\": [1]}"),
              HasSubstr("'pi_thresholds[0]': expected a number"));
  EXPECT_THAT(msg("{\"power_exponent\": -1}"), HasSubstr("power_exponent"));
  EXPECT_THAT(msg("{\"uncertainty\": {\"pi_weights[x]\": 1}}"), HasSubstr("unknown field"));
}

TEST(Channel, PrandtlIshlinskiiIsAWeightedSumOfPlayOperators) {
  // Triangle wave 0 -> 2 -> 0 -> 2 N.
  std::vector<double> t, f;
  for (int i = 0; i <= 300; ++i) {
    t.push_back(0.01 * i);
    const double ph = std::fmod(0.01 * i, 2.0);
    f.push_back(ph < 1 ? 2 * ph : 2 * (2 - ph));
  }
  ChannelInput in;
  in.t = t.data();
  in.force = f.data();
  in.n = static_cast<int>(t.size());
  std::vector<double> pi, play1, play2;
  EffectParams p;
  p.pi_thresholds = {0, 0.1, 0.3};
  p.pi_weights = {2, 1, 1};  // relative: 0.5, 0.25, 0.25
  ApplyChannel(p, in, &pi);
  EffectParams a;
  a.hysteresis_width = 0.2;
  ApplyChannel(a, in, &play1);
  EffectParams b;
  b.hysteresis_width = 0.6;
  ApplyChannel(b, in, &play2);
  for (size_t i = 0; i < t.size(); ++i)
    EXPECT_NEAR(pi[i], 0.5 * f[i] + 0.25 * play1[i] + 0.25 * play2[i], 1e-12);
  // Residual after release = sum w r = 0.25 * 0.1 + 0.25 * 0.3.
  EXPECT_NEAR(pi[200], 0.1, 1e-9);
  // A single operator of radius r is the play operator of width 2r.
  EffectParams single;
  single.pi_thresholds = {0.1};
  single.pi_weights = {3};
  std::vector<double> s;
  ApplyChannel(single, in, &s);
  for (size_t i = 0; i < t.size(); ++i) EXPECT_NEAR(s[i], play1[i], 1e-12);
}

TEST(Channel, PowerLawAndItsInverse) {
  std::vector<double> t = {0, 1, 2, 3}, f = {0, 1, 4, -2};
  ChannelInput in;
  in.t = t.data();
  in.force = f.data();
  in.n = 4;
  EffectParams p;
  p.power_exponent = 0.5;
  p.full_scale = 4;
  std::vector<double> out;
  ApplyChannel(p, in, &out);
  EXPECT_NEAR(out[0], 0, 1e-12);
  EXPECT_NEAR(out[1], 4 * std::sqrt(0.25), 1e-12);
  EXPECT_NEAR(out[2], 4, 1e-12);
  EXPECT_NEAR(out[3], -4 * std::sqrt(0.5), 1e-12);  // odd extension
  SensorModel m;
  m.effects = p;
  m.gain = -20;
  m.offset = 1000;
  for (double force : {0.3, 1.0, 2.5, 7.0}) {
    std::vector<double> tt = {0}, ff = {force};
    const double reading = PredictReading(m, tt, ff, {})[0];
    EXPECT_NEAR(CorrectReading(m, reading, 0, 0), force, 1e-9);
  }
  // Simulation with the new effects runs and matches the channel.
  SensorModel sm;
  sm.effects.pi_thresholds = {0, 0.05, 0.15};
  sm.effects.pi_weights = {0.4, 0.3, 0.3};
  sm.effects.power_exponent = 0.85;
  sm.effects.full_scale = 8;
  auto run = SimulateSensor(sm, Short());
  ASSERT_TRUE(run.ok()) << run.status();
  const auto pred = PredictReading(sm, run->t, run->reference, run->shear);
  double worst = 0;
  for (size_t i = 0; i < pred.size(); ++i)
    worst = std::max(worst, std::abs(pred[i] - run->reading[i]));
  EXPECT_LT(worst, 1e-3);  // play operators on the 4x finer simulation grid
}

TEST(Simulate, WriterProducesTheAuditFormat) {
  SensorModel m;
  m.noise = 0.01;
  m.effects.hysteresis_width = 0.1;
  auto run = SimulateSensor(m, Short());
  ASSERT_TRUE(run.ok());
  const tactforce::testing::TempDir temp("tactforce_sim_writer_test");
  const std::filesystem::path dir = temp.path();
  ASSERT_TRUE(WriteSimRun(*run, dir.string()).ok());
  auto data = audit::ReadMeasuredCsv((dir / "run.csv").string());
  ASSERT_TRUE(data.ok()) << data.status();
  EXPECT_EQ(data->t.size(), run->t.size());
  EXPECT_EQ(data->shear.size(), run->t.size());
  auto model = LoadSensorModel((dir / "model.json").string());
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_EQ(model->effects.hysteresis_width, 0.1);
  EXPECT_TRUE(std::filesystem::exists(dir / "fingertip.csv"));
  std::filesystem::remove_all(dir);
}

TEST(Channel, PredictReadingMatchesTheSimulationWithoutNoise) {
  SensorModel m;
  m.gain = 2;
  m.offset = -1;
  m.effects.hysteresis_width = 0.2;
  m.effects.threshold = 0.3;
  m.effects.curvature = 0.05;
  auto run = SimulateSensor(m, Short());
  ASSERT_TRUE(run.ok());
  auto pred = PredictReading(m, run->t, run->reference, run->shear);
  // The simulation runs the play operator on a 4x finer grid, so a peak
  // between samples can move the hysteresis state by a little.
  for (size_t i = 0; i < pred.size(); ++i) EXPECT_NEAR(pred[i], run->reading[i], 1e-3);
  // Static inversion recovers the force above the threshold.
  SensorModel s;
  s.gain = -30;
  s.offset = 900;
  s.effects.curvature = 0.04;
  s.effects.drift = 0.01;
  for (double f : {0.5, 2.0, 7.0}) {
    const double r = PredictReading(s, {0.0, 3.0}, {f, f}, {})[1];
    EXPECT_NEAR(CorrectReading(s, r, 3.0, 0), f, 1e-9);
  }
}

}  // namespace
}  // namespace tactforce::sim
