// Audit: bad input, units (counts with a negative gain), two streams, the
// report files, the extended model round trip, a given model, real data.
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>

#include "gmock/gmock.h"
#include "gtest/gtest.h"
#include "hidden_effects.h"
#include "absl/strings/str_cat.h"
#include "tactforce/io/json.h"
#include "support/temp_dir.h"

namespace tactforce::audit {
namespace {

using ::testing::HasSubstr;
namespace fs = std::filesystem;

std::string Message(const absl::Status& s) { return std::string(s.message()); }

std::string SimCsv(const sim::SensorModel& m, uint64_t seed = 5, double seconds = 12,
                   double rate = 200) {
  sim::SimOptions o;
  o.seconds = seconds;
  o.rate = rate;
  o.seed = seed;
  auto run = sim::SimulateSensor(m, o);
  return run.ok() ? sim::SimRunCsv(*run) : "";
}

AuditOptions Quick() {
  AuditOptions o;
  o.downstream_gain = false;
  return o;
}

// ---- bad input -------------------------------------------------------------

TEST(BadInput, MissingColumns) {
  auto d = ParseMeasuredCsv("t,reference\n0,1\n1,2\n", "run.csv");
  EXPECT_THAT(Message(d.status()), HasSubstr("run.csv: missing column(s) reading"));
}

TEST(BadInput, TooFewSamplesSaysHowMany) {
  std::string csv = "t,reference,reading\n";
  for (int i = 0; i < 12; ++i)
    csv += std::to_string(i * 0.01) + "," + std::to_string(i) + "," + std::to_string(2 * i) + "\n";
  auto d = ParseMeasuredCsv(csv, "run.csv");
  EXPECT_THAT(Message(d.status()), HasSubstr("too few samples: 12 valid rows"));
  EXPECT_THAT(Message(d.status()), HasSubstr("needs at least 40"));
}

TEST(BadInput, ConstantReference) {
  std::string csv = "t,reference,reading\n";
  for (int i = 0; i < 100; ++i)
    csv += std::to_string(i * 0.01) + ",2," + std::to_string(i % 7) + "\n";
  auto d = ParseMeasuredCsv(csv, "run.csv");
  EXPECT_THAT(Message(d.status()), HasSubstr("column 'reference' is constant"));
}

TEST(BadInput, NanRowsAreSkippedAndCounted) {
  sim::SensorModel m;
  m.noise = 0.02;
  std::istringstream in(SimCsv(m));
  std::string line, csv;
  int row = 0;
  while (std::getline(in, line)) {
    if (row > 0 && row % 500 == 0) csv += "0.0,nan,1,0,0\n";  // 4 NaN rows
    if (row == 1000) csv += "5.0,,1,0,0\n";                   // empty field counts too
    csv += line + "\n";
    ++row;
  }
  auto d = ParseMeasuredCsv(csv, "run.csv");
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(d->skipped_nan_rows, 5);
  auto rep = RunAudit(*d, Quick());
  ASSERT_TRUE(rep.ok()) << rep.status();
  EXPECT_EQ(rep->skipped_nan_rows, 5);
  EXPECT_THAT(AuditReportJson(*rep), HasSubstr("\"skipped_nan_rows\": 5"));
  EXPECT_TRUE(rep->nominal_adequate);
}

TEST(BadInput, UnsortedTimeNamesTheLine) {
  std::string csv = "t,reference,reading\n";
  for (int i = 0; i < 100; ++i) {
    const double t = i == 50 ? 0.2 : i * 0.01;
    csv += std::to_string(t) + "," + std::to_string(i % 10) + "," + std::to_string(i % 10) + "\n";
  }
  auto d = ParseMeasuredCsv(csv, "run.csv");
  EXPECT_THAT(Message(d.status()), HasSubstr("run.csv:52: column 't': time not increasing"));
}

// Found by the csv fuzzer: a trial number past int's range was cast
// (undefined behaviour) instead of named.
TEST(BadInput, TrialOutOfIntRangeNamesTheLine) {
  std::string csv = "t,reference,reading,trial\n";
  for (int i = 0; i < 60; ++i) {
    csv += std::to_string(i * 0.01) + "," + std::to_string(i % 7) + "," + std::to_string(i % 5) +
           "," + (i == 3 ? "1e300" : "0") + "\n";
  }
  auto d = ParseMeasuredCsv(csv, "run.csv");
  EXPECT_THAT(Message(d.status()),
              HasSubstr("run.csv:5: column 'trial': not an integer in int's range (1e+300)"));
}

TEST(BadInput, NotANumberNamesLineAndColumn) {
  auto d = ParseMeasuredCsv("t,reference,reading\n0,1,2\n0.1,abc,2\n", "run.csv");
  EXPECT_THAT(Message(d.status()), HasSubstr("run.csv:3"));
  EXPECT_THAT(Message(d.status()), HasSubstr("reference"));
}

TEST(BadInput, Options) {
  auto d = ParseMeasuredCsv(SimCsv(sim::SensorModel{}), "run.csv");
  ASSERT_TRUE(d.ok());
  AuditOptions o = Quick();
  o.heldout_fraction = 0.9;
  EXPECT_THAT(Message(RunAudit(*d, o).status()), HasSubstr("heldout_fraction"));
  EXPECT_FALSE(ParseEffect("backlash").ok());
}

TEST(Trials, TimeRestartsPerTrial) {
  std::string a = SimCsv(sim::SensorModel{}, 1, 4), b = SimCsv(sim::SensorModel{}, 2, 4);
  // Second trial: same times, trial column = 1.
  std::istringstream in(b);
  std::string line, csv = a;
  std::getline(in, line);
  while (std::getline(in, line)) csv += line.substr(0, line.rfind(',')) + ",1\n";
  auto d = ParseMeasuredCsv(csv, "run.csv");
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_EQ(d->segment_starts.size(), 2u);
  // A trial that resumes later is rejected.
  auto bad = ParseMeasuredCsv(csv + "9,1,1,0,0\n", "run.csv");
  EXPECT_THAT(Message(bad.status()), HasSubstr("resumes"));
}

// ---- units -----------------------------------------------------------------

// The hidden case's effects with the reading in N (gain 1) and in counts
// with a negative gain (-45 counts/N, offset 1010), both audited.
struct NewtonsAndCounts {
  sim::SensorModel n_model, c_model;
  absl::StatusOr<AuditReport> rn, rc;
};

NewtonsAndCounts AuditInNewtonsAndCounts(const testing::HiddenCase& hc) {
  NewtonsAndCounts out;
  out.n_model = hc.model;
  out.n_model.units = "N";
  out.n_model.gain = 1;
  out.n_model.offset = 0;
  out.c_model = out.n_model;
  out.c_model.units = "counts";
  out.c_model.gain = -45;  // reading falls as force rises
  out.c_model.offset = 1010;
  auto run_n = sim::SimulateSensor(out.n_model, hc.sim);
  auto run_c = sim::SimulateSensor(out.c_model, hc.sim);
  if (!run_n.ok() || !run_c.ok()) {
    out.rn = out.rc = absl::InternalError("simulation failed");
    return out;
  }
  auto dn = ParseMeasuredCsv(sim::SimRunCsv(*run_n), "n.csv");
  auto dc = ParseMeasuredCsv(sim::SimRunCsv(*run_c), "c.csv");
  if (!dn.ok() || !dc.ok()) {
    out.rn = out.rc = absl::InternalError("measured CSV rejected");
    return out;
  }
  out.rn = RunAudit(*dn, Quick());
  AuditOptions oc = Quick();
  oc.reading_units = "counts";
  out.rc = RunAudit(*dc, oc);
  return out;
}

TEST(Units, CountsWithNegativeGainAuditedLikeNewtons) {
  for (Effect e : {Effect::kSaturation, Effect::kDeadzone, Effect::kHysteresis, Effect::kDelay}) {
    const NewtonsAndCounts r =
        AuditInNewtonsAndCounts(testing::MakeHiddenCase({e}, 4242 + static_cast<int>(e)));
    ASSERT_TRUE(r.rn.ok() && r.rc.ok()) << r.rn.status() << r.rc.status();
    ASSERT_FALSE(r.rc->causes.empty() || r.rn->causes.empty()) << EffectName(e);
    EXPECT_EQ(r.rc->causes[0].effect, EffectName(e));
    EXPECT_EQ(r.rn->causes[0].effect, EffectName(e));
    // (The nominal gain is biased by the unmodelled effect; the extended one is not.)
    EXPECT_LT(r.rc->nominal_model.gain, 0);
    EXPECT_NEAR(r.rc->extended_model.gain, -45, 0.5);
    EXPECT_TRUE(testing::CheckParameters(e, r.c_model.effects, r.rc->causes[0]).ok)
        << EffectName(e);
    for (const auto& [k, v] : r.rn->causes[0].parameters)
      EXPECT_NEAR(r.rc->causes[0].parameters.at(k), v, 1e-3 * (1 + std::abs(v)))
          << EffectName(e) << " " << k;
    EXPECT_NEAR(r.rc->gain, r.rn->gain, 0.5) << EffectName(e);
  }
}

// The second forms in counts with a negative gain: the same effect, form and
// parameters as in N (the noise is the same per seed; the units only scale).
TEST(Units, NewFormsInCountsWithNegativeGain) {
  for (auto [e, form] : {std::pair{Effect::kHysteresis, testing::HiddenForm::kPrandtlIshlinskii},
                         std::pair{Effect::kNonlinearity, testing::HiddenForm::kPowerLaw}}) {
    const NewtonsAndCounts r =
        AuditInNewtonsAndCounts(testing::MakeHiddenCase({e}, 5151 + static_cast<int>(e), form));
    ASSERT_TRUE(r.rn.ok() && r.rc.ok()) << r.rn.status() << r.rc.status();
    ASSERT_FALSE(r.rc->causes.empty() || r.rn->causes.empty()) << EffectName(e);
    EXPECT_EQ(r.rc->causes[0].effect, EffectName(e));
    EXPECT_EQ(r.rc->causes[0].form, r.rn->causes[0].form);
    EXPECT_NEAR(r.rc->extended_model.gain, -45, 0.5);
    EXPECT_TRUE(testing::CheckParameters(e, r.c_model.effects, r.rc->causes[0]).ok)
        << EffectName(e);
    EXPECT_TRUE(testing::CheckParameters(e, r.n_model.effects, r.rn->causes[0]).ok)
        << EffectName(e);
    EXPECT_NEAR(r.rc->gain, r.rn->gain, 0.5) << EffectName(e);
  }
}

// ---- two streams -------------------------------------------------------------

TEST(TwoStreams, AlignedByInterpolatingTheReference) {
  sim::SensorModel m;
  m.noise = 0.01;
  m.gain = 3;
  m.effects.delay = 0.03;
  sim::SimOptions o;
  o.seconds = 15;
  o.rate = 1000;
  o.seed = 11;
  auto run = sim::SimulateSensor(m, o);
  ASSERT_TRUE(run.ok());
  // Reference stream at 1 kHz on its clock; reading stream at 250 Hz on a
  // clock 100 s ahead.
  std::string ref = "t,value,shear\n", rd = "t,value\n";
  for (size_t i = 0; i < run->t.size(); ++i) {
    ref += absl::StrCat(run->t[i], ",", run->reference[i], ",", run->shear[i], "\n");
    if (i % 4 == 1) rd += absl::StrCat(run->t[i] + 100.0, ",", run->reading[i], "\n");
  }
  auto rt = io::ParseCsv(ref, "ref.csv");
  auto qt = io::ParseCsv(rd, "reading.csv");
  ASSERT_TRUE(rt.ok() && qt.ok());
  EXPECT_THAT(Message(AlignStreams(*rt, *qt).status()), HasSubstr("do not overlap"));
  AlignOptions ao;
  ao.clock_offset = 100.0;
  auto d = AlignStreams(*rt, *qt, ao);
  ASSERT_TRUE(d.ok()) << d.status();
  EXPECT_NEAR(static_cast<double>(d->t.size()), run->t.size() / 4.0, 2);
  auto rep = RunAudit(*d, Quick());
  ASSERT_TRUE(rep.ok());
  ASSERT_FALSE(rep->causes.empty());
  EXPECT_EQ(rep->causes[0].effect, "delay");
  EXPECT_NEAR(rep->causes[0].parameters.at("delay"), 0.03, 0.004);
  auto missing = io::ParseCsv("t,v\n0,1\n", "ref.csv");
  EXPECT_THAT(Message(AlignStreams(*missing, *qt).status()),
              HasSubstr("ref.csv: missing column(s) value"));
}

// ---- report, extended model, given model -----------------------------------------

// The two-form effects in report.json ("form", PI arrays) and in the written
// extended model (loads, re-simulates as audited).
TEST(Report, FormsAndPrandtlIshlinskiiArraysRoundTrip) {
  struct Case {
    Effect e;
    testing::HiddenForm form;
    const char* name;
  };
  for (const Case& k :
       {Case{Effect::kHysteresis, testing::HiddenForm::kPrandtlIshlinskii, "prandtl_ishlinskii"},
        Case{Effect::kNonlinearity, testing::HiddenForm::kPowerLaw, "power_law"},
        Case{Effect::kHysteresis, testing::HiddenForm::kDefault, "play"}}) {
    testing::HiddenCase hc = testing::MakeHiddenCase({k.e}, 1100003, k.form);
    AuditOptions o = Quick();
    o.reading_units = hc.model.units;
    auto rep = RunAudit(hc.data, o);
    ASSERT_TRUE(rep.ok()) << rep.status();
    ASSERT_FALSE(rep->causes.empty());
    EXPECT_EQ(rep->causes[0].effect, EffectName(k.e));
    EXPECT_EQ(rep->causes[0].form, k.name);
    const tactforce::testing::TempDir temp(std::string("tactforce_audit_forms_") + k.name);
    const fs::path dir = temp.path();
    ASSERT_TRUE(WriteAuditReport(*rep, dir.string()).ok());
    std::ifstream in(dir / "report.json");
    std::stringstream ss;
    ss << in.rdbuf();
    auto j = io::ParseJson(ss.str(), "report.json");
    ASSERT_TRUE(j.ok()) << j.status();
    const auto& c0 = j->Find("causes")->array().at(0);
    const auto* params = c0.Find("parameters");
    ASSERT_NE(params, nullptr);
    ASSERT_NE(params->Find("form"), nullptr);
    EXPECT_EQ(params->Find("form")->string(), k.name);
    auto model = sim::LoadSensorModel((dir / "extended_model.json").string());
    ASSERT_TRUE(model.ok()) << model.status();
    if (k.form == testing::HiddenForm::kPrandtlIshlinskii) {
      const auto* w = params->Find("pi_weights");
      const auto* r = params->Find("pi_thresholds");
      ASSERT_TRUE(w && r && w->is_array() && r->is_array());
      EXPECT_EQ(w->array().size(), r->array().size());
      double sum = 0;
      for (const auto& v : w->array()) {
        EXPECT_GE(v.number(), 0);
        sum += v.number();
      }
      EXPECT_NEAR(sum, 1, 1e-9);
      EXPECT_EQ(model->effects.pi_weights.size(), w->array().size());
      EXPECT_EQ(model->effects.hysteresis_width, 0);
      EXPECT_NEAR(rep->causes[0].parameters.at("loop_width"),
                  testing::PiLoopWidth(hc.model.effects),
                  0.03 + 0.2 * testing::PiLoopWidth(hc.model.effects));
    }
    if (k.form == testing::HiddenForm::kPowerLaw)
      EXPECT_NEAR(model->effects.power_exponent, hc.model.effects.power_exponent, 0.01);
    auto pred = sim::PredictReading(*model, hc.data.t, hc.data.reference, hc.data.shear,
                                    hc.data.segment_starts);
    for (size_t i = 0; i < pred.size(); ++i)
      ASSERT_NEAR(pred[i], rep->predicted_extended[i], 1e-6) << k.name;
    EXPECT_THAT(FormatAuditSummary(*rep), HasSubstr(k.name));
  }
}

TEST(Report, FilesAndExtendedModelRoundTrip) {
  testing::HiddenCase hc = testing::MakeHiddenCase({Effect::kHysteresis, Effect::kDelay}, 77);
  AuditOptions o;
  o.reading_units = hc.model.units;
  auto rep = RunAudit(hc.data, o);
  ASSERT_TRUE(rep.ok()) << rep.status();
  ASSERT_GE(rep->causes.size(), 2u);
  const tactforce::testing::TempDir temp("tactforce_audit_report_test");
  const fs::path dir = temp.path();
  ASSERT_TRUE(WriteAuditReport(*rep, dir.string()).ok());
  for (const char* f :
       {"report.json", "summary.txt", "extended_model.json", "reading_vs_reference.svg",
        "residual_vs_reference.svg", "residual_vs_time.svg"})
    EXPECT_TRUE(fs::exists(dir / f)) << f;

  std::ifstream in(dir / "report.json");
  std::stringstream ss;
  ss << in.rdbuf();
  auto j = io::ParseJson(ss.str(), "report.json");
  ASSERT_TRUE(j.ok()) << j.status();
  ASSERT_NE(j->Find("nominal_adequate"), nullptr);
  EXPECT_FALSE(j->Find("nominal_adequate")->boolean());
  const auto* causes = j->Find("causes");
  ASSERT_NE(causes, nullptr);
  ASSERT_EQ(causes->array().size(), rep->causes.size());
  for (const auto& c : causes->array())
    for (const char* k :
         {"effect", "parameters", "heldout_rms_before", "heldout_rms_after", "gain"})
      EXPECT_NE(c.Find(k), nullptr) << k;
  const auto* path = j->Find("extended_model");
  ASSERT_NE(path, nullptr);
  EXPECT_EQ(path->string(), (dir / "extended_model.json").string());

  // The extended model loads, re-simulates the run as the audit did, and
  // drives the simulation.
  auto model = sim::LoadSensorModel(path->string());
  ASSERT_TRUE(model.ok()) << model.status();
  EXPECT_GT(model->effects.hysteresis_width, 0);
  EXPECT_GT(model->effects.delay, 0);
  EXPECT_GT(model->uncertainty.at("delay"), 0);
  auto pred = sim::PredictReading(*model, hc.data.t, hc.data.reference, hc.data.shear,
                                  hc.data.segment_starts);
  for (size_t i = 0; i < pred.size(); ++i) ASSERT_NEAR(pred[i], rep->predicted_extended[i], 1e-6);
  sim::SimOptions so = hc.sim;
  so.seconds = 3;
  EXPECT_TRUE(sim::SimulateSensor(*model, so).ok());
  EXPECT_GT(rep->gain, 0);
  EXPECT_LT(rep->heldout_rms_after, rep->heldout_rms_before);

  // SVGs are well-formed enough: start/end tags.
  std::ifstream svg(dir / "residual_vs_time.svg");
  std::string text((std::istreambuf_iterator<char>(svg)), std::istreambuf_iterator<char>());
  EXPECT_EQ(text.rfind("<svg", 0), 0u);
  EXPECT_THAT(text, HasSubstr("</svg>"));
  const std::string summary = FormatAuditSummary(*rep);
  EXPECT_THAT(summary, HasSubstr("Causes (strongest first)"));
  fs::remove_all(dir);
}

TEST(GivenModel, TrueModelIsAdequate) {
  testing::HiddenCase hc = testing::MakeHiddenCase({Effect::kHysteresis}, 31);
  AuditOptions o = Quick();
  o.model = hc.model;
  auto rep = RunAudit(hc.data, o);
  ASSERT_TRUE(rep.ok()) << rep.status();
  EXPECT_TRUE(rep->nominal_adequate);
  ASSERT_TRUE(rep->given_model_heldout_rms.has_value());
  // Without the model the hysteresis is named.
  auto plain = RunAudit(hc.data, Quick());
  ASSERT_TRUE(plain.ok());
  ASSERT_FALSE(plain->causes.empty());
  EXPECT_EQ(plain->causes[0].effect, "hysteresis");
}

// ---- the absolute floor of a cause's gain -------------------------------------

// Noise-free sensors with drawn gains and offsets, ideal or with one drawn
// dead zone, through the CSV the simulator writes (9 significant digits):
// once the true effect is named the residual is round-off, and no further
// cause may be named however large its relative gain on it. With the floor
// at 0 (the relative gain alone) the same runs are counted on stderr.
TEST(GainFloor, RoundOffResidualNamesNoFurtherCause) {
  std::mt19937_64 rng(2025);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int extra_without_floor = 0;
  double largest_gain_without_floor = 0, its_rms = 0;
  constexpr int kRuns = 8;
  for (int run = 0; run < kRuns; ++run) {
    sim::SensorModel m;
    m.gain = (unit(rng) < 0.5 ? -1 : 1) * (0.5 + 60 * unit(rng));
    m.offset = 2000 * (unit(rng) - 0.5);
    const bool deadzone = run % 2 == 1;
    if (deadzone) m.effects.threshold = 0.2 + 0.3 * unit(rng);
    auto d = ParseMeasuredCsv(SimCsv(m, 40 + run, 8, 100), "noise_free.csv");
    ASSERT_TRUE(d.ok()) << d.status();
    auto rep = RunAudit(*d, Quick());
    ASSERT_TRUE(rep.ok()) << rep.status();
    ASSERT_EQ(rep->causes.size(), deadzone ? 1u : 0u)
        << "run " << run << " (gain " << m.gain << "): last named " << rep->causes.back().effect
        << " with gain " << rep->causes.back().gain << " % on a held-out RMS of "
        << rep->causes.back().heldout_rms_before;
    if (deadzone) {
      EXPECT_EQ(rep->causes[0].effect, "deadzone") << "run " << run;
    }
    AuditOptions no_floor = Quick();
    no_floor.min_rms_drop = 0;
    auto relative_only = RunAudit(*d, no_floor);
    ASSERT_TRUE(relative_only.ok());
    if (relative_only->causes.size() > rep->causes.size()) {
      ++extra_without_floor;
      const Cause& extra = relative_only->causes[rep->causes.size()];
      if (extra.gain > largest_gain_without_floor) {
        largest_gain_without_floor = extra.gain;
        its_rms = extra.heldout_rms_before / std::abs(m.gain);
      }
    }
  }
  std::cerr << "[ floor ] " << kRuns
            << " noise-free runs: a cause on the round-off residual in 0 with the floor, in "
            << extra_without_floor << " without it (largest gain " << largest_gain_without_floor
            << " % on a held-out RMS of " << its_rms << " N)\n";
}

TEST(GainFloor, OptionIsChecked) {
  auto d = ParseMeasuredCsv(SimCsv(sim::SensorModel{}, 3, 8, 100), "ideal.csv");
  ASSERT_TRUE(d.ok());
  AuditOptions o = Quick();
  o.min_rms_drop = -1;
  EXPECT_THAT(Message(RunAudit(*d, o).status()), HasSubstr("min_rms_drop"));
}

// ---- real data ---------------------------------------------------------------

TEST(RealData, PiezoresistiveTaxelCalibration) {
  const char* src = std::getenv("TACTFORCE_SOURCE_DIR");
  const fs::path dir = fs::path(src ? src : ".") / ".." / "shared" / "data" / "tactile";
  if (!fs::exists(dir))
    GTEST_SKIP() << "real tactile data not present at " << dir << " (../shared is optional)";
  int files = 0;
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() != ".csv") continue;
    ++files;
    auto d = ReadMeasuredCsv(entry.path().string());
    ASSERT_TRUE(d.ok()) << d.status();
    AuditOptions o;
    o.reading_units = "ADC counts";
    auto rep = RunAudit(*d, o);
    ASSERT_TRUE(rep.ok()) << rep.status();
    std::cout << FormatAuditSummary(*rep);
    EXPECT_FALSE(rep->nominal_adequate) << entry.path();
    ASSERT_FALSE(rep->causes.empty());
    EXPECT_GT(rep->causes[0].gain, 0);
    EXPECT_GT(rep->gain, 0);
    EXPECT_LT(rep->nominal_model.gain, 0) << "the ADC reading falls as force rises";
    const tactforce::testing::TempDir temp("tactforce_audit_real_" + entry.path().stem().string());
    const fs::path out = temp.path();
    ASSERT_TRUE(WriteAuditReport(*rep, out.string()).ok());
    EXPECT_TRUE(fs::exists(out / "report.json"));
  }
  if (files == 0) GTEST_SKIP() << "no CSV files in " << dir;
}

}  // namespace
}  // namespace tactforce::audit
