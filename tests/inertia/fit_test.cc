#include "tactforce/inertia/fit.h"

#include <cmath>
#include <string>

#include <gtest/gtest.h>

#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/truth.h"
#include "test_util.h"

namespace tactforce::inertia {
namespace {

using testing::ShortSimulation;

void ExpectNear(const InertialParameters& truth, const InertialParameters& est, double rel) {
  EXPECT_NEAR(est.mass, truth.mass, rel * truth.mass);
  const double scale = std::max(truth.com.norm(), 0.01);
  EXPECT_LT((est.com - truth.com).norm(), rel * scale)
      << est.com.transpose() << " vs " << truth.com.transpose();
  const Eigen::Matrix3d d = est.inertia_com.Matrix() - truth.inertia_com.Matrix();
  EXPECT_LT(d.norm(), rel * truth.inertia_com.Matrix().norm()) << "\n" << est.inertia_com.Matrix();
}

TEST(FitInertia, BaselineLsMeasuredKinematicsNoiseFreeExact) {
  for (const char* object : {"seed-table1", "box"}) {
    for (SimulationMode mode : {SimulationMode::kWristWrench, SimulationMode::kInHand}) {
      SCOPED_TRACE(std::string(object) + (mode == SimulationMode::kInHand ? " in-hand" : " wrist"));
      absl::StatusOr<SimulationResult> sim = SimulateInertia(ShortSimulation(object, mode, true));
      ASSERT_TRUE(sim.ok()) << sim.status();
      InertiaOptions o;
      o.method = InertiaMethod::kBaselineLs;
      absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
      ASSERT_TRUE(fit.ok()) << fit.status();
      ExpectNear(sim->truth.params, fit->params, 1e-6);
      EXPECT_TRUE(fit->physically_consistent);
      EXPECT_TRUE(fit->poorly_excited.empty());
    }
  }
}

TEST(FitInertia, SharedToolsRecoveredByBaselineLs) {
  const std::optional<std::string> dir = testing::SharedInertiaDir();
  if (!dir) GTEST_SKIP() << "../shared/data/inertia not found (set TACTFORCE_SOURCE_DIR); skipping";
  for (const char* tool : {"Hammer", "Screwdriver", "Pliers", "Ruler", "C_Clamp"}) {
    SCOPED_TRACE(tool);
    absl::StatusOr<InertiaSamples> s = ReadInertiaCsvFile(*dir + "/" + tool + ".csv");
    ASSERT_TRUE(s.ok()) << s.status();
    absl::StatusOr<InertiaTruth> truth = ReadTruthJsonFile(*dir + "/" + tool + ".truth.json");
    ASSERT_TRUE(truth.ok()) << truth.status();
    InertiaOptions o;
    o.method = InertiaMethod::kBaselineLs;
    if (truth->gravity_world) o.gravity = *truth->gravity_world;
    absl::StatusOr<InertiaFit> fit = FitInertia(*s, o);
    ASSERT_TRUE(fit.ok()) << fit.status();
    const InertiaErrors e = CompareInertia(truth->params, fit->params);
    EXPECT_LT(e.mass_percent, 1e-3);
    EXPECT_LT(e.com_mm, 1e-3);
    EXPECT_LT(e.riemannian, 1e-4);
    EXPECT_TRUE(e.consistent);
  }
}

// Noise-free poses and forces (no measured kinematics): every method
// recovers the truth; BASELINE_LS and FACTOR_GRAPH only up to their
// finite-difference bias, CONSTRAINED (smoothing fit) almost exactly.
TEST(FitInertia, AllMethodsRecoverNoiseFreeSimulation) {
  for (SimulationMode mode : {SimulationMode::kInHand, SimulationMode::kWristWrench}) {
    SimulationOptions so = ShortSimulation("seed-table1", mode, false);
    so.rate_hz = 200;
    so.duration = 2.0;
    absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
    ASSERT_TRUE(sim.ok()) << sim.status();
    const InertialParameters& truth = sim->truth.params;
    const double size = EquivalentBoxSize(truth);
    for (InertiaMethod m :
         {InertiaMethod::kBaselineLs, InertiaMethod::kFactorGraph, InertiaMethod::kConstrained}) {
      SCOPED_TRACE(std::string(ToString(m)) +
                   (mode == SimulationMode::kInHand ? " in-hand" : " wrist"));
      InertiaOptions o;
      o.method = m;
      absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
      ASSERT_TRUE(fit.ok()) << fit.status();
      const InertiaErrors e = CompareInertia(truth, fit->params);
      // FACTOR_GRAPH carries the paper's O(dt) bias (forces of the first of
      // three samples): at 200 Hz about 0.4 in Riemannian distance.
      const double tol = m == InertiaMethod::kConstrained  ? 1e-4
                         : m == InertiaMethod::kBaselineLs ? 1e-2
                                                           : 1e-2;
      const double riem = m == InertiaMethod::kConstrained  ? 1e-4
                          : m == InertiaMethod::kBaselineLs ? 1e-2
                                                            : 0.5;
      EXPECT_LT(e.mass_percent, 100 * tol);
      EXPECT_LT(e.com_mm / 1000.0, tol * size);
      EXPECT_LT(e.riemannian, riem);
      EXPECT_TRUE(fit->physically_consistent);
      EXPECT_GT(fit->iterations, 0);
      EXPECT_EQ(fit->singular_values.size(), 10u);
    }
  }
}

// The factor graph's error is its discretisation bias: it halves when the
// sample rate doubles (noise-free data), so the implementation converges.
TEST(FitInertia, FactorGraphBiasIsFirstOrderInTheSamplePeriod) {
  double previous = 0;
  for (double rate : {100.0, 200.0, 400.0}) {
    SimulationOptions so = ShortSimulation("seed-table1", SimulationMode::kWristWrench, false);
    so.rate_hz = rate;
    so.duration = 1.0;
    absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
    ASSERT_TRUE(sim.ok());
    InertiaOptions o;
    o.method = InertiaMethod::kFactorGraph;
    absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
    ASSERT_TRUE(fit.ok()) << fit.status();
    const double err = CompareInertia(sim->truth.params, fit->params).riemannian;
    if (previous > 0) {
      EXPECT_NEAR(err / previous, 0.5, 0.1) << "rate " << rate;
    }
    previous = err;
  }
}

TEST(FitInertia, ConstrainedRecoversExactlyWithMeasuredKinematics) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("box", SimulationMode::kInHand, true));
  ASSERT_TRUE(sim.ok()) << sim.status();
  absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, InertiaOptions{});
  ASSERT_TRUE(fit.ok()) << fit.status();
  ExpectNear(sim->truth.params, fit->params, 1e-6);
  EXPECT_TRUE(fit->physically_consistent);
}

// Light object, noisy wrist data: least squares often leaves the
// physically consistent set; CONSTRAINED never does.
TEST(FitInertia, ConstrainedConsistentWhereLeastSquaresIsNot) {
  int ls_inconsistent = 0;
  for (const char* level : {"low", "moderate", "high"}) {
    SimulationOptions so = ShortSimulation("box", SimulationMode::kWristWrench, true);
    so.noise = *NadeauNoise(level);
    for (uint64_t seed : {1, 2, 3}) {
      SCOPED_TRACE(std::string(level) + " seed " + std::to_string(seed));
      so.seed = seed;
      absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
      ASSERT_TRUE(sim.ok()) << sim.status();
      InertiaOptions o;
      o.noise.force_sigma = so.noise.force_sigma;
      o.noise.torque_sigma = so.noise.torque_sigma;
      o.noise.linear_acceleration_sigma = so.noise.linear_acceleration_sigma;
      o.noise.angular_acceleration_sigma = so.noise.angular_acceleration_sigma;
      o.method = InertiaMethod::kBaselineLs;
      absl::StatusOr<InertiaFit> ls = FitInertia(sim->samples, o);
      ASSERT_TRUE(ls.ok()) << ls.status();
      ls_inconsistent += !ls->physically_consistent;
      o.method = InertiaMethod::kConstrained;
      absl::StatusOr<InertiaFit> c = FitInertia(sim->samples, o);
      ASSERT_TRUE(c.ok()) << c.status();
      EXPECT_TRUE(c->physically_consistent);
      EXPECT_TRUE(IsPhysicallyConsistent(c->params));
      EXPECT_LT(CompareInertia(sim->truth.params, c->params).mass_percent, 5.0);
    }
  }
  EXPECT_GT(ls_inconsistent, 0) << "the test data should make least squares inconsistent sometimes";
}

TEST(FitInertia, UnexcitedDirectionsAreNamedNotAnError) {
  // Static object: gravity along z only identifies m, m*cx, m*cy.
  InertiaSamples s;
  s.source = ForceSource::kWrench;
  for (int i = 0; i < 20; ++i) {
    InertiaSample x;
    x.t = 0.01 * i;
    x.force = Vec3(0, 0, 9.81 * 0.5);
    x.torque = Vec3(0.02, 0.03, 0.0).cross(Vec3(0, 0, 9.81 * 0.5));  // CoM (0.02, 0.03, .)
    s.samples.push_back(x);
  }
  for (InertiaMethod m : {InertiaMethod::kBaselineLs, InertiaMethod::kConstrained}) {
    InertiaOptions o;
    o.method = m;
    absl::StatusOr<InertiaFit> fit = FitInertia(s, o);
    ASSERT_TRUE(fit.ok()) << fit.status();
    EXPECT_NEAR(fit->params.mass, 0.5, 1e-6);
    EXPECT_NEAR(fit->params.com.x(), 0.02, 1e-6);
    EXPECT_NEAR(fit->params.com.y(), 0.03, 1e-6);
    EXPECT_GE(fit->poorly_excited.size(), 6u);
    std::string all;
    for (const auto& d : fit->poorly_excited) all += d + "; ";
    EXPECT_NE(all.find("Ixx"), std::string::npos) << all;
    EXPECT_NE(all.find("m*cz"), std::string::npos) << all;
  }
}

TEST(FitInertia, HullConstrainsTheCom) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("box", SimulationMode::kInHand, false));
  ASSERT_TRUE(sim.ok()) << sim.status();
  // A hull that stops 3 mm short of the true CoM in x.
  const Vec3 c = sim->truth.params.com;
  std::vector<Vec3> hull;
  for (double x : {c.x() - 0.1, c.x() - 0.003})
    for (double y : {c.y() - 0.1, c.y() + 0.1})
      for (double z : {c.z() - 0.1, c.z() + 0.1}) hull.push_back(Vec3(x, y, z));
  for (InertiaMethod m : {InertiaMethod::kConstrained, InertiaMethod::kFactorGraph}) {
    SCOPED_TRACE(ToString(m));
    InertiaOptions o;
    o.method = m;
    o.hull = hull;
    absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
    ASSERT_TRUE(fit.ok()) << fit.status();
    if (m == InertiaMethod::kConstrained) {
      EXPECT_TRUE(fit->com_in_hull) << fit->params.com.transpose();
      EXPECT_LE(fit->params.com.x(), c.x() - 0.003 + 1e-7);
      EXPECT_TRUE(fit->physically_consistent);
    } else {
      // The paper's soft constraint: pulled to the boundary, not exactly on it.
      EXPECT_LT(fit->params.com.x(), c.x() - 0.002) << fit->params.com.transpose();
    }
  }
}

// CONSTRAINED's steps report once per fit, not once per re-weighting round:
// the weak entropic regulariser (no prior), the SLSQP hull step when the
// unconstrained optimum leaves the hull; with a prior, no regulariser.
TEST(FitInertia, ConstrainedStepsNoteOncePerFit) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("box", SimulationMode::kInHand, false));
  ASSERT_TRUE(sim.ok()) << sim.status();
  const Vec3 c = sim->truth.params.com;
  InertiaOptions o;
  o.method = InertiaMethod::kConstrained;
  for (double x : {c.x() - 0.1, c.x() - 0.003})
    for (double y : {c.y() - 0.1, c.y() + 0.1})
      for (double z : {c.z() - 0.1, c.z() + 0.1}) o.hull.push_back(Vec3(x, y, z));
  ASSERT_GE(o.reweighting_rounds, 2);
  auto count = [](const InertiaFit& f, const std::string& prefix) {
    int n = 0;
    for (const std::string& note : f.notes) n += note.rfind(prefix, 0) == 0;
    return n;
  };
  absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
  ASSERT_TRUE(fit.ok()) << fit.status();
  EXPECT_EQ(count(*fit, "weak entropic regularisation"), 1);
  EXPECT_EQ(count(*fit, "CoM-in-hull constraint active (SLSQP)"), 1);
  EXPECT_EQ(count(*fit, "SLSQP for the hull rows failed"), 0);
  EXPECT_LE(fit->params.com.x(), c.x() - 0.003 + 1e-7);

  o.hull.clear();
  o.prior = InertiaPrior{sim->truth.params, 1.0};
  fit = FitInertia(sim->samples, o);
  ASSERT_TRUE(fit.ok()) << fit.status();
  EXPECT_EQ(count(*fit, "weak entropic regularisation"), 0);
  EXPECT_EQ(count(*fit, "CoM-in-hull constraint active"), 0);
}

// A hull that does not contain the object's CoM contradicts the data: the
// fit says so with the distance; a CoM just outside (noise) does not warn.
TEST(FitInertia, WarnsWhenTheDataPutTheComOutsideTheHull) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("box", SimulationMode::kInHand, false));
  ASSERT_TRUE(sim.ok()) << sim.status();
  const Vec3 c = sim->truth.params.com;
  auto warnings = [&](double short_by, std::string* text) {
    InertiaOptions o;
    o.method = InertiaMethod::kConstrained;
    for (double x : {c.x() - 0.1, c.x() - short_by})
      for (double y : {c.y() - 0.1, c.y() + 0.1})
        for (double z : {c.z() - 0.1, c.z() + 0.1}) o.hull.push_back(Vec3(x, y, z));
    absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
    EXPECT_TRUE(fit.ok()) << fit.status();
    int n = 0;
    for (const std::string& note : fit->notes) {
      if (note.rfind("warning: the data put the CoM", 0) == 0) {
        ++n;
        *text = note;
      }
    }
    return n;
  };
  std::string text;
  EXPECT_EQ(warnings(0.003, &text), 0) << text;
  ASSERT_EQ(warnings(0.04, &text), 1);
  // "... 40.1 mm outside ...": the distance the data ask for, within 2 mm.
  const double mm = std::stod(text.substr(text.find("CoM ") + 4));
  EXPECT_NEAR(mm, 40.0, 2.0) << text;
}

TEST(FitInertia, OptionErrorsNameTheField) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("box", SimulationMode::kInHand, false));
  ASSERT_TRUE(sim.ok());
  InertiaOptions o;
  o.hull = {Vec3(0, 0, 0), Vec3(0.1, 0, 0), Vec3(0, 0.1, 0), Vec3(0, 0, 0.1)};
  o.prior = InertiaPrior{sim->truth.params, 1.0};  // CoM (0.02, -0.01, 0.03) is outside
  absl::StatusOr<InertiaFit> f = FitInertia(sim->samples, o);
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.status().message().find("prior.com (0.02, -0.01, 0.03) is outside the hull"),
            std::string::npos)
      << f.status();
  InertiaOptions bad;
  bad.noise.force_sigma = -1;
  EXPECT_NE(FitInertia(sim->samples, bad).status().message().find("noise.force_sigma"),
            std::string::npos);
  InertiaOptions flat;
  flat.hull = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(1, 1, 0)};
  EXPECT_NE(FitInertia(sim->samples, flat).status().message().find("hull: degenerate"),
            std::string::npos);
}

TEST(FitInertia, PriorPullsFactorGraphAndConstrained) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("seed-table1", SimulationMode::kInHand, false));
  ASSERT_TRUE(sim.ok());
  for (InertiaMethod m : {InertiaMethod::kConstrained, InertiaMethod::kFactorGraph}) {
    InertiaOptions o;
    o.method = m;
    o.prior = InertiaPrior{sim->truth.params, 10.0};
    absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
    ASSERT_TRUE(fit.ok()) << fit.status();
    EXPECT_LT(CompareInertia(sim->truth.params, fit->params).riemannian, 0.5) << ToString(m);
  }
}

TEST(FitInertia, ProgressInterruptAndMethodNames) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("box", SimulationMode::kInHand, false));
  ASSERT_TRUE(sim.ok());
  for (InertiaMethod m :
       {InertiaMethod::kBaselineLs, InertiaMethod::kFactorGraph, InertiaMethod::kConstrained}) {
    InertiaOptions o;
    o.method = m;
    double last = -1;
    bool monotone = true;
    o.progress = [&](double f) {
      monotone = monotone && f >= last && f <= 1.0;
      last = f;
    };
    absl::StatusOr<InertiaFit> fit = FitInertia(sim->samples, o);
    ASSERT_TRUE(fit.ok());
    EXPECT_EQ(last, 1.0);
    EXPECT_TRUE(monotone);
    EXPECT_GT(fit->cpu_seconds, 0.0);
    const std::string text = DescribeFit(*fit);
    EXPECT_NE(text.find("mass: "), std::string::npos) << text;
    EXPECT_NE(text.find("physically consistent: yes"), std::string::npos) << text;
    EXPECT_EQ(*ParseInertiaMethod(ToString(m)), m);
  }
  InertiaOptions o;
  o.method = InertiaMethod::kFactorGraph;
  o.interrupt = [] { return true; };
  EXPECT_EQ(FitInertia(sim->samples, o).status().code(), absl::StatusCode::kCancelled);
  EXPECT_FALSE(ParseInertiaMethod("ransac").ok());
}

}  // namespace
}  // namespace tactforce::inertia
