// End-to-end planner tests: analytic grasps, and the property test that
// cross-checks the geometric fast path against the Ipopt reference.
#include <cmath>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "tactforce/planner/examples.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/validation.h"

namespace tactforce::planner {
namespace {

const double kCosHalf12 = std::cos(std::numbers::pi / 12);

PlanResult SolveOk(SolverKind kind, const PlanProblem& p, const PlanOptions& o) {
  absl::StatusOr<PlanResult> r = MakeSolver(kind)->Solve(p, o);
  EXPECT_TRUE(r.ok()) << r.status();
  return r.ok() ? *r : PlanResult{};
}

Eigen::VectorXd Stack(const std::vector<Vec3>& forces) {
  Eigen::VectorXd f(3 * forces.size());
  for (size_t i = 0; i < forces.size(); ++i) f.segment<3>(3 * i) = forces[i];
  return f;
}

ExampleGrasp Example(const std::string& name) {
  for (ExampleGrasp& g : BuiltInGrasps()) {
    if (g.name == name) return g;
  }
  ADD_FAILURE() << "no example " << name;
  return {};
}

TEST(Planner, SpherePinchMatchesTheClosedForm) {
  const ExampleGrasp g = Example("sphere-pinch");
  const double m = g.problem.object.mass, weight = m * 9.81;
  const double mu = g.problem.contacts[0].friction;
  for (double kappa : {0.0, 1.0, 2.5}) {
    PlanOptions o = g.options;
    o.confidence = kappa;
    for (SolverKind kind : {SolverKind::kGeometric, SolverKind::kIpopt}) {
      const PlanResult r = SolveOk(kind, g.problem, o);
      ASSERT_EQ(r.status, PlanStatus::kOptimal) << r.message;
      // Both fingers carry half the weight; they squeeze just enough for the
      // pyramid (a facet points along gravity) plus kappa * rho_n.
      const double rho = std::hypot(g.problem.contacts[0].sigma, g.problem.contacts[1].sigma) / 2;
      const double squeeze =
          std::max(g.problem.contacts[0].min_normal_force, weight / (2 * mu * kCosHalf12)) +
          kappa * rho;
      for (int i = 0; i < 2; ++i) {
        EXPECT_NEAR(r.forces[i].z(), weight / 2, 1e-6) << ToString(kind);
        EXPECT_NEAR(r.normal_forces[i], squeeze, 1e-6) << ToString(kind) << " kappa " << kappa;
        EXPECT_NEAR(r.forces[i].y(), 0.0, 1e-6);
        EXPECT_NEAR(r.normal_force_sigma[i], rho, 1e-12);
      }
      EXPECT_NEAR(r.objective, 2 * (squeeze * squeeze + weight * weight / 4), 1e-5);
      EXPECT_NEAR(r.min_margin, 0.0, 1e-6);
      // The active rows' slack is round-off: reported as exactly 0, never -2.8e-17.
      if (kind == SolverKind::kGeometric) EXPECT_EQ(r.min_margin, 0.0);
    }
  }
}

TEST(Planner, CylinderFourFingersShareTheWeight) {
  const ExampleGrasp g = Example("cylinder-4f");
  PlanOptions o = g.options;
  o.confidence = 0.0;
  const double weight = g.problem.object.mass * 9.81;
  const double mu = g.problem.contacts[0].friction;
  const double squeeze =
      std::max(g.problem.contacts[0].min_normal_force, weight / (4 * mu * kCosHalf12));
  for (SolverKind kind : {SolverKind::kGeometric, SolverKind::kIpopt}) {
    const PlanResult r = SolveOk(kind, g.problem, o);
    ASSERT_EQ(r.status, PlanStatus::kOptimal) << r.message;
    for (int i = 0; i < 4; ++i) {
      EXPECT_NEAR(r.forces[i].z(), weight / 4, 1e-6);
      EXPECT_NEAR(r.normal_forces[i], squeeze, 1e-6);
    }
  }
}

TEST(Planner, ExamplesAreFeasibleAndBothBackendsAgree) {
  for (const ExampleGrasp& g : BuiltInGrasps()) {
    const PlanResult r = SolveOk(SolverKind::kCrossCheck, g.problem, g.options);
    ASSERT_EQ(r.status, PlanStatus::kOptimal) << g.name << ": " << r.message;
    ASSERT_TRUE(r.cross_check.has_value());
    EXPECT_TRUE(r.cross_check->agree) << g.name << " diff " << r.cross_check->max_force_diff;
    EXPECT_LE(r.cross_check->max_force_diff, 1e-5);
    EXPECT_GE(r.min_margin, -1e-9);
    EXPECT_EQ(r.solver, SolverKind::kCrossCheck);
  }
}

TEST(Planner, WrenchGraspNeedsMoreSqueezeWhenSensorsAreWorse) {
  const ExampleGrasp g = Example("wrench-3f");
  PlanProblem noisy = g.problem;
  for (Contact& c : noisy.contacts) c.sigma = 0.0;
  const PlanResult exact = SolveOk(SolverKind::kGeometric, noisy, g.options);
  const PlanResult robust = SolveOk(SolverKind::kGeometric, g.problem, g.options);
  ASSERT_EQ(exact.status, PlanStatus::kOptimal);
  ASSERT_EQ(robust.status, PlanStatus::kOptimal);
  EXPECT_GT(robust.objective, exact.objective);
  EXPECT_GT(robust.normal_force_sigma[0], 0.0);
}

TEST(Planner, InfeasibleTorqueAboutThePinchAxisIsAResultNotAnError) {
  PlanProblem p = Example("sphere-pinch").problem;
  p.external_wrench.torque = Vec3(0.05, 0, 0);
  for (SolverKind kind : {SolverKind::kGeometric, SolverKind::kIpopt, SolverKind::kCrossCheck}) {
    const PlanResult r = SolveOk(kind, p, PlanOptions{});
    EXPECT_EQ(r.status, PlanStatus::kInfeasible) << ToString(kind);
    EXPECT_NE(r.message.find("rank 5"), std::string::npos) << r.message;
    EXPECT_TRUE(r.forces.empty());
  }
}

TEST(Planner, InfeasibleFrictionNamesTheBlockingContact) {
  PlanProblem p = Example("cylinder-4f").problem;
  for (Contact& c : p.contacts) c.friction = 0.0;
  const PlanResult r = SolveOk(SolverKind::kGeometric, p, PlanOptions{});
  EXPECT_EQ(r.status, PlanStatus::kInfeasible);
  EXPECT_NE(r.message.find("contact "), std::string::npos) << r.message;
  EXPECT_NE(r.message.find("friction cone facet"), std::string::npos) << r.message;
}

TEST(Planner, MaxNormalForceCanMakeAGraspInfeasible) {
  PlanProblem p = Example("sphere-pinch").problem;
  for (Contact& c : p.contacts) c.max_normal_force = 0.3;  // the weight needs ~0.52 N
  const PlanResult g = SolveOk(SolverKind::kCrossCheck, p, PlanOptions{});
  EXPECT_EQ(g.status, PlanStatus::kInfeasible);
  ASSERT_TRUE(g.cross_check.has_value());
  EXPECT_EQ(g.cross_check->ipopt_status, PlanStatus::kInfeasible) << g.cross_check->ipopt_message;
}

// The property test of the planner issue: >= 2,000 seeded random grasps.
TEST(PlannerProperty, GeometricAndIpoptAgreeAndPlansAreRobust) {
  std::mt19937_64 rng(424242);
  std::mt19937_64 sample_rng(7);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const auto geometric = MakeSolver(SolverKind::kGeometric);
  const auto ipopt = MakeSolver(SolverKind::kIpopt);
  int optimal = 0, infeasible = 0, constructed_infeasible = 0;
  double worst_diff = 0.0;
  const int kGrasps = 2000;
  for (int trial = 0; trial < kGrasps; ++trial) {
    const RandomGrasp grasp = MakeRandomGrasp(rng);
    PlanOptions options;
    options.confidence = (trial % 4 == 0) ? 0.0 : 1.0 + (trial % 3);
    options.cone_sides = 4 + trial % 13;
    SCOPED_TRACE(testing::Message() << "grasp " << trial);
    absl::StatusOr<PlanResult> g = geometric->Solve(grasp.problem, options);
    absl::StatusOr<PlanResult> i = ipopt->Solve(grasp.problem, options);
    ASSERT_TRUE(g.ok() && i.ok());
    ASSERT_EQ(g->status, i->status) << "geometric: " << g->message << " | ipopt: " << i->message;
    if (grasp.infeasible_by_construction) {
      ++constructed_infeasible;
      EXPECT_EQ(g->status, PlanStatus::kInfeasible);
    }
    if (g->status != PlanStatus::kOptimal) {
      ++infeasible;
      continue;
    }
    ++optimal;
    double diff = 0.0;
    for (size_t c = 0; c < g->forces.size(); ++c) {
      diff = std::max(diff, (g->forces[c] - i->forces[c]).cwiseAbs().maxCoeff());
    }
    worst_diff = std::max(worst_diff, diff);
    EXPECT_LE(diff, 1e-5);

    // Equilibrium to 1e-8 and every tightened row.
    const PlanProblem validated = *ValidateProblem(grasp.problem, options);
    const PreparedProblem prep = Prepare(validated, options);
    const Eigen::MatrixXd rows = prep.rows.Dense(prep.num_contacts());
    const Eigen::VectorXd f = Stack(g->forces);
    EXPECT_LE((prep.equilibrium.grasp_matrix * f - prep.equilibrium.wrench).cwiseAbs().maxCoeff(),
              1e-8);
    const Eigen::VectorXd slack = prep.rows.rhs - rows * f;
    EXPECT_GE(slack.minCoeff(), -1e-9);
    double scale = 1.0;
    for (const Vec3& force : g->forces) scale = std::max(scale, force.lpNorm<Eigen::Infinity>());
    if (std::abs(slack.minCoeff()) <= kMarginRoundOff * scale) {
      EXPECT_EQ(g->min_margin, 0.0);  // round-off is reported as 0
    } else {
      EXPECT_NEAR(g->min_margin, slack.minCoeff(), 1e-12);
    }

    // 1,000 forces inside the trusted ellipsoid {f + L y : |y| <= kappa}
    // satisfy the untightened cone and normal-force rows.
    const Eigen::MatrixXd& L = prep.ellipsoid.factor;
    const int dim = static_cast<int>(L.cols());
    if (dim == 0) continue;
    for (int s = 0; s < 1000; ++s) {
      Eigen::VectorXd y(dim);
      for (int k = 0; k < dim; ++k) y(k) = gauss(sample_rng);
      // Uniform in the ball; every tenth sample on its boundary (the worst case).
      const double radius =
          options.confidence * (s % 10 == 0 ? 1.0 : std::pow(unit(sample_rng), 1.0 / dim));
      const Eigen::VectorXd sample = f + L * (radius * y.normalized());
      const Eigen::VectorXd nominal_slack = prep.rows.nominal_rhs - rows * sample;
      ASSERT_GE(nominal_slack.minCoeff(), -1e-8) << "sample " << s;
    }
  }
  RecordProperty("optimal", optimal);
  RecordProperty("infeasible", infeasible);
  std::cout << "[ property ] " << kGrasps << " grasps: " << optimal << " optimal, " << infeasible
            << " infeasible (" << constructed_infeasible
            << " by construction); worst |f_geo - f_ipopt| = " << worst_diff << " N\n";
  EXPECT_GE(optimal, kGrasps / 4) << "the generator should make mostly solvable grasps";
  EXPECT_GE(infeasible, kGrasps / 20);
}

TEST(PlannerProperty, ExactConeLiesBetweenThePyramids) {
  std::mt19937_64 rng(99);
  const auto ipopt = MakeSolver(SolverKind::kIpopt);
  int compared = 0;
  for (int trial = 0; trial < 150; ++trial) {
    RandomGraspOptions ro;
    ro.infeasible_fraction = 0.0;
    const RandomGrasp grasp = MakeRandomGrasp(rng, ro);
    PlanOptions pyramid;
    pyramid.confidence = 0.0;
    pyramid.cone_sides = 6 + trial % 10;
    PlanOptions exact = pyramid;
    exact.cone = ConeModel::kExact;
    PlanProblem outer = grasp.problem;  // the circumscribed pyramid
    for (Contact& c : outer.contacts) c.friction /= std::cos(std::numbers::pi / pyramid.cone_sides);
    const PlanResult inner_r = SolveOk(SolverKind::kIpopt, grasp.problem, pyramid);
    const PlanResult exact_r = SolveOk(SolverKind::kIpopt, grasp.problem, exact);
    const PlanResult outer_r = SolveOk(SolverKind::kGeometric, outer, pyramid);
    if (inner_r.status != PlanStatus::kOptimal) continue;
    SCOPED_TRACE(testing::Message() << "grasp " << trial);
    ASSERT_EQ(exact_r.status, PlanStatus::kOptimal) << exact_r.message;
    ASSERT_EQ(outer_r.status, PlanStatus::kOptimal) << outer_r.message;
    const double tol = 1e-6 * std::max(1.0, inner_r.objective);
    EXPECT_LE(exact_r.objective, inner_r.objective + tol);
    EXPECT_GE(exact_r.objective, outer_r.objective - tol);
    ++compared;
  }
  EXPECT_GE(compared, 50);
}

}  // namespace
}  // namespace tactforce::planner
