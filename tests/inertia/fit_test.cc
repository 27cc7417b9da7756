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
  EXPECT_LT((est.com - truth.com).norm(), rel * scale) << est.com.transpose() << " vs " << truth.com.transpose();
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

}  // namespace
}  // namespace tactforce::inertia
