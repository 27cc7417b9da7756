// The factor-graph variants of the paper's ablation (InertiaOptions::fg_variant):
// each does what its name says.
#include <algorithm>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/simulate.h"
#include "test_util.h"

namespace tactforce::inertia {
namespace {

constexpr FactorGraphVariant kAll[] = {
    FactorGraphVariant::kBaselineFg, FactorGraphVariant::kNoConstraint,
    FactorGraphVariant::kConstraint, FactorGraphVariant::kConstraintPrior};

// A consistent object drawn from `seed`: mass 0.2-2 kg, CoM within 5 cm of
// the origin, principal moments of a box with edges 5-20 cm, random axes.
InertialParameters DrawObject(uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  InertialParameters p;
  p.mass = 0.2 + 1.8 * u(rng);
  p.com = Vec3(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 0.1;
  const Vec3 e(0.05 + 0.15 * u(rng), 0.05 + 0.15 * u(rng), 0.05 + 0.15 * u(rng));
  const Vec3 d(e.y() * e.y() + e.z() * e.z(), e.x() * e.x() + e.z() * e.z(),
               e.x() * e.x() + e.y() * e.y());
  const Eigen::Matrix3d R =
      Eigen::Quaterniond(
          Eigen::Vector4d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5).normalized())
          .toRotationMatrix();
  p.inertia_com = InertiaTensor::FromMatrix(R * (p.mass / 12.0 * d).asDiagonal() * R.transpose());
  return p;
}

SimulationResult Simulate(uint64_t seed, double force_variance = 0.0) {
  const InertialParameters truth = DrawObject(seed);
  absl::StatusOr<SimulatedObject> object = ObjectFromParameters("drawn", truth);
  EXPECT_TRUE(object.ok()) << object.status();
  SimulationOptions so = testing::ShortSimulation("drawn", SimulationMode::kWristWrench, false);
  so.custom = *object;
  so.duration = 2.0;
  so.rate_hz = 200;
  so.noise.force_sigma = std::sqrt(force_variance);
  so.seed = seed;
  absl::StatusOr<SimulationResult> sim = SimulateInertia(so);
  EXPECT_TRUE(sim.ok()) << sim.status();
  return *sim;
}

InertiaOptions Options(FactorGraphVariant v) {
  InertiaOptions o;
  o.method = InertiaMethod::kFactorGraph;
  o.factor_graph.variant = v;
  return o;
}

TEST(FactorGraphVariant, SpellingsRoundTrip) {
  for (FactorGraphVariant v : kAll) {
    absl::StatusOr<FactorGraphVariant> back = ParseFactorGraphVariant(ToString(v));
    ASSERT_TRUE(back.ok()) << back.status();
    EXPECT_EQ(*back, v);
  }
  EXPECT_EQ(*ParseFactorGraphVariant("FACTOR_GRAPH_VARIANT_BASELINE_FG"),
            FactorGraphVariant::kBaselineFg);
  EXPECT_EQ(*ParseFactorGraphVariant("FACTOR_GRAPH_VARIANT_NO_C"),
            FactorGraphVariant::kNoConstraint);
  EXPECT_EQ(*ParseFactorGraphVariant("factor_graph_variant_c_g"),
            FactorGraphVariant::kConstraintPrior);
  EXPECT_EQ(*ParseFactorGraphVariant("FG_C"), FactorGraphVariant::kConstraint);
  absl::StatusOr<FactorGraphVariant> bad = ParseFactorGraphVariant("fg-x");
  ASSERT_FALSE(bad.ok());
  EXPECT_NE(bad.status().message().find("fg_variant"), std::string::npos) << bad.status();
  EXPECT_EQ(InertiaOptions().factor_graph.variant,
            FactorGraphVariant::kConstraint);  // today's factor-graph
}

TEST(FactorGraphVariant, PriorVariantWithoutPriorIsAnErrorNamingTheField) {
  const SimulationResult sim = Simulate(11);
  absl::StatusOr<InertiaFit> fit =
      FitInertia(sim.samples, Options(FactorGraphVariant::kConstraintPrior));
  ASSERT_FALSE(fit.ok());
  EXPECT_EQ(fit.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_EQ(fit.status().message().rfind("prior:", 0), 0u) << fit.status();
  // Other methods do not care about the factor-graph variant.
  InertiaOptions other = Options(FactorGraphVariant::kConstraintPrior);
  other.method = InertiaMethod::kConstrained;
  EXPECT_TRUE(ValidateInertiaOptions(other).ok());
  other.factor_graph.variant = FactorGraphVariant::kNoConstraint;
  absl::StatusOr<InertiaFit> constrained = FitInertia(sim.samples, other);
  ASSERT_TRUE(constrained.ok()) << constrained.status();
  EXPECT_NE(std::find(constrained->notes.begin(), constrained->notes.end(),
                      "fg_variant fg-no-c ignored by constrained"),
            constrained->notes.end());
}

// Data of an object whose every force is negated: the least-squares answer
// is -pi (negative mass, negative inertia). Only variants without the
// constraint factor may go there.
TEST(FactorGraphVariant, WithoutConstraintsANegativeMassIsAccepted) {
  std::mt19937_64 seeds(20260);
  for (int trial = 0; trial < 2; ++trial) {
    const uint64_t seed = seeds() % 100000;
    SCOPED_TRACE(seed);
    SimulationResult sim = Simulate(seed);
    for (InertiaSample& s : sim.samples.samples) s.force = -s.force, s.torque = -s.torque;
    const double m = sim.truth.params.mass;
    for (FactorGraphVariant v : kAll) {
      SCOPED_TRACE(ToString(v));
      InertiaOptions o = Options(v);
      if (v == FactorGraphVariant::kConstraintPrior) o.prior = InertiaPrior{sim.truth.params, 1.0};
      absl::StatusOr<InertiaFit> fit = FitInertia(sim.samples, o);
      ASSERT_TRUE(fit.ok()) << fit.status();
      if (v == FactorGraphVariant::kBaselineFg || v == FactorGraphVariant::kNoConstraint) {
        EXPECT_NEAR(fit->params.mass, -m, 0.05 * m);  // the unconstrained optimum
        EXPECT_FALSE(fit->physically_consistent);
      } else {
        // The m > 0 factor pulls it towards 0, softly: a cost active when
        // violated is "not enough to ensure feasibility" (the paper, Sec. VI).
        EXPECT_GT(fit->params.mass, -0.5 * m);
      }
    }
  }
}

// A hull that excludes the true CoM: fg-no-c ignores it (c in the hull is
// one of "every constraint"), fg-c pulls c to it.
TEST(FactorGraphVariant, NoConstraintIgnoresTheHull) {
  const uint64_t seed = std::mt19937_64(977)() % 100000;
  SCOPED_TRACE(seed);
  const SimulationResult sim = Simulate(seed);
  const Vec3 c = sim.truth.params.com;
  std::vector<Vec3> hull;  // a 2 cm cube 3 cm beside the CoM along x
  for (int i = 0; i < 8; ++i)
    hull.push_back(c + Vec3(0.03 + 0.02 * (i & 1), 0.02 * ((i >> 1) & 1) - 0.01,
                            0.02 * ((i >> 2) & 1) - 0.01));
  double distance[2];
  int k = 0;
  for (FactorGraphVariant v :
       {FactorGraphVariant::kNoConstraint, FactorGraphVariant::kConstraint}) {
    InertiaOptions o = Options(v);
    o.hull = hull;
    absl::StatusOr<InertiaFit> fit = FitInertia(sim.samples, o);
    ASSERT_TRUE(fit.ok()) << fit.status();
    distance[k++] = 0.03 - (fit->params.com.x() - c.x());  // how far short of the hull's face
  }
  EXPECT_LT(distance[0] - 0.03, 0.0 + 0.003) << "fg-no-c moved the CoM";
  EXPECT_GT(distance[0], 0.025);
  EXPECT_LT(distance[1], 0.002) << "fg-c left the CoM outside the hull";
}

// Normal data drawn from a seed: every variant fits; the baseline's
// inertial variables are the entries of H (notes), the others [m, c, L, R];
// fg-c without a prior equals the default options bit for bit; fg-c-g with
// the truth as prior is at least as close as fg-c.
TEST(FactorGraphVariant, EveryVariantFitsDrawnObjects) {
  std::mt19937_64 seeds(424242);
  const uint64_t seed = seeds() % 100000;
  SCOPED_TRACE(seed);
  const SimulationResult sim = Simulate(seed, 0.1);
  double eq38[4];
  for (int i = 0; i < 4; ++i) {
    const FactorGraphVariant v = kAll[i];
    SCOPED_TRACE(ToString(v));
    InertiaOptions o = Options(v);
    o.noise.force_sigma = std::sqrt(0.1);
    if (v == FactorGraphVariant::kConstraintPrior) o.prior = InertiaPrior{sim.truth.params, 1.0};
    absl::StatusOr<InertiaFit> fit = FitInertia(sim.samples, o);
    ASSERT_TRUE(fit.ok()) << fit.status();
    ASSERT_FALSE(fit->notes.empty());
    EXPECT_EQ(fit->notes[0].rfind(std::string("factor-graph variant ") + ToString(v), 0), 0u)
        << fit->notes[0];
    const bool raw = fit->notes[0].find("H_xx..H_yz") != std::string::npos;
    EXPECT_EQ(raw, v == FactorGraphVariant::kBaselineFg);
    EXPECT_EQ(fit->notes[0].find(" L, ") == std::string::npos,
              v == FactorGraphVariant::kBaselineFg);
    const InertiaErrors e = CompareInertia(sim.truth.params, fit->params);
    EXPECT_LT(e.mass_percent, 5.0);
    eq38[i] = e.paper_metric;
    if (v == FactorGraphVariant::kConstraint) {
      InertiaOptions plain;
      plain.method = InertiaMethod::kFactorGraph;
      plain.noise.force_sigma = o.noise.force_sigma;
      absl::StatusOr<InertiaFit> def = FitInertia(sim.samples, plain);
      ASSERT_TRUE(def.ok());
      EXPECT_EQ(def->standard, fit->standard);
    }
  }
  EXPECT_LE(eq38[3], eq38[2] + 1e-6);
}

}  // namespace
}  // namespace tactforce::inertia
