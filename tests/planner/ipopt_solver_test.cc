// Tests of the Ipopt reference backend through the public API
// MakeSolver(SolverKind::kIpopt)->Solve(problem, options).
#include <atomic>
#include <chrono>
#include <cmath>
#include <numbers>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "planner/fixtures.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner {
namespace {

using fixtures::Finger;
using fixtures::Options;
using fixtures::Pinch;
using fixtures::ThreeFingerGrasp;

constexpr double kG = 9.81;

PlanResult SolveIpopt(const PlanProblem& problem, const PlanOptions& options,
                      const SolveControl& control = {}) {
  absl::StatusOr<PlanResult> r = MakeSolver(SolverKind::kIpopt)->Solve(problem, options, control);
  EXPECT_TRUE(r.ok()) << r.status();
  return r.ok() ? *r : PlanResult{};
}

// Largest |G f - b| of a result.
double EquilibriumError(const PlanProblem& problem, const PlanOptions& options,
                        const PlanResult& r) {
  const ForceEquilibrium eq = ComputeForceEquilibrium(problem, options.rank_tolerance);
  Eigen::VectorXd f(3 * r.forces.size());
  for (size_t i = 0; i < r.forces.size(); ++i) f.segment<3>(3 * i) = r.forces[i];
  return (eq.grasp_matrix * f - eq.wrench).cwiseAbs().maxCoeff();
}

// Pinch, pyramid, kappa = 0: each finger carries m g / 2 along z and squeezes
// N = max(min force, m g / (2 mu cos(pi/k))): with facet normals at angles
// 2 pi j / k and k a multiple of 4, a facet normal points along gravity.
TEST(IpoptSolver, PinchPyramidMatchesTheClosedForm) {
  const double m = 0.5, mu = 0.5;
  const PlanOptions o = Options(ConeModel::kPyramid);
  for (double min_force : {0.0, 40.0}) {
    const PlanResult r = SolveIpopt(Pinch(m, mu, min_force), o);
    ASSERT_EQ(r.status, PlanStatus::kOptimal) << r.message;
    EXPECT_EQ(r.solver, SolverKind::kIpopt);
    EXPECT_GT(r.iterations, 0);
    const double squeeze = std::max(min_force, m * kG / (2 * mu * std::cos(std::numbers::pi / 12)));
    ASSERT_EQ(r.forces.size(), 2u);
    EXPECT_NEAR(r.forces[0].x(), -squeeze, 1e-6);
    EXPECT_NEAR(r.forces[1].x(), squeeze, 1e-6);
    for (const Vec3& f : r.forces) {
      EXPECT_NEAR(f.y(), 0.0, 1e-7);
      EXPECT_NEAR(f.z(), m * kG / 2, 1e-7);
    }
    EXPECT_NEAR(r.objective, 2 * (squeeze * squeeze + m * kG * m * kG / 4), 1e-5);
    EXPECT_GE(r.min_margin, -1e-6);
  }
}

// min_normal_force == max_normal_force leaves the rows no interior.
TEST(IpoptSolver, EqualForceBoundsPinTheSqueeze) {
  PlanProblem p = Pinch(0.5, 0.5, 30.0);
  for (Contact& c : p.contacts) c.max_normal_force = 30.0;
  for (ConeModel cone : {ConeModel::kPyramid, ConeModel::kExact}) {
    const PlanResult r = SolveIpopt(p, Options(cone));
    ASSERT_EQ(r.status, PlanStatus::kOptimal) << r.message;
    EXPECT_NEAR(r.normal_forces[0], 30.0, 1e-6);
    EXPECT_NEAR(r.normal_forces[1], 30.0, 1e-6);
  }
}

// The exact cone needs only N = m g / (2 mu).
TEST(IpoptSolver, PinchExactConeMatchesTheClosedForm) {
  const double m = 0.5, mu = 0.5;
  const PlanResult r = SolveIpopt(Pinch(m, mu), Options(ConeModel::kExact));
  ASSERT_EQ(r.status, PlanStatus::kOptimal) << r.message;
  const double squeeze = m * kG / (2 * mu);
  EXPECT_NEAR(r.forces[0].x(), -squeeze, 1e-6);
  EXPECT_NEAR(r.forces[1].x(), squeeze, 1e-6);
  for (const Vec3& f : r.forces) EXPECT_NEAR(f.z(), m * kG / 2, 1e-7);
  EXPECT_GE(r.min_margin, -1e-6);
}

// mu = 0.05 needs a squeeze of ~49 N for 0.5 kg; a 10 N force limit makes
// it infeasible, which Ipopt must report as such (not as a failure).
TEST(IpoptSolver, LowFrictionUnderAForceLimitIsInfeasible) {
  PlanProblem p = Pinch(0.5, 0.05);
  for (Contact& c : p.contacts) c.max_normal_force = 10.0;
  for (ConeModel cone : {ConeModel::kPyramid, ConeModel::kExact}) {
    const PlanResult r = SolveIpopt(p, Options(cone));
    EXPECT_EQ(r.status, PlanStatus::kInfeasible) << r.message;
    EXPECT_NE(r.message.find("Ipopt"), std::string::npos) << r.message;
    EXPECT_TRUE(r.forces.empty());
  }
  // Without the limit the same friction holds the weight by squeezing hard.
  const PlanResult free = SolveIpopt(Pinch(0.5, 0.05), Options(ConeModel::kExact));
  ASSERT_EQ(free.status, PlanStatus::kOptimal) << free.message;
  EXPECT_NEAR(free.normal_forces[0], 0.5 * kG / (2 * 0.05), 1e-5);
}

TEST(IpoptSolver, FrictionlessPinchCannotHoldTheWeight) {
  for (ConeModel cone : {ConeModel::kPyramid, ConeModel::kExact}) {
    const PlanResult r = SolveIpopt(Pinch(0.5, 0.0), Options(cone));
    EXPECT_EQ(r.status, PlanStatus::kInfeasible) << r.message;
    EXPECT_NE(r.message.find("cannot resist"), std::string::npos) << r.message;
  }
}

// A frictionless table under the centre of mass carries most of the weight.
// The fingers squeeze with their minimum force N = 2 N and take what their
// friction allows of the weight, z = mu cos(pi/k) N (pyramid) or mu N
// (exact): sharing the load lowers sum |f|^2 and raising N would cost more
// (d/dN at N = 2: 4 N (1 + mu^2) - 4 mu (m g - 2 mu N) > 0).
TEST(IpoptSolver, FrictionlessTableCarriesTheRestOfTheWeight) {
  const double m = 0.5, mu = 0.5, squeeze = 2.0;
  PlanProblem p = Pinch(m, mu, squeeze);
  Contact table = Finger(Vec3(0, 0, -0.03), Vec3(0, 0, 1), 0.0);
  table.kind = ContactKind::kExtrinsic;
  p.contacts.push_back(table);
  for (ConeModel cone : {ConeModel::kPyramid, ConeModel::kExact}) {
    const PlanResult r = SolveIpopt(p, Options(cone));
    ASSERT_EQ(r.status, PlanStatus::kOptimal) << r.message;
    const double z =
        mu * squeeze * (cone == ConeModel::kPyramid ? std::cos(std::numbers::pi / 12) : 1.0);
    EXPECT_LE((r.forces[0] - Vec3(-squeeze, 0, z)).norm(), 1e-6) << r.forces[0].transpose();
    EXPECT_LE((r.forces[1] - Vec3(squeeze, 0, z)).norm(), 1e-6) << r.forces[1].transpose();
    EXPECT_LE((r.forces[2] - Vec3(0, 0, m * kG - 2 * z)).norm(), 1e-6);
  }
  // Alone, the table determines the force completely.
  PlanProblem alone;
  alone.object.mass = 0.5;
  alone.contacts.push_back(table);
  const PlanResult r = SolveIpopt(alone, Options(ConeModel::kExact));
  ASSERT_EQ(r.status, PlanStatus::kOptimal) << r.message;
  EXPECT_LE((r.forces[0] - Vec3(0, 0, 0.5 * kG)).norm(), 1e-9);
  EXPECT_EQ(r.iterations, 0);
}

// One finger on the side of a sphere would have to hold the weight by
// friction alone with zero normal force: the unique equilibrium is outside
// the cone.
TEST(IpoptSolver, UniqueEquilibriumOutsideTheConeIsInfeasible) {
  PlanProblem p;
  p.object.mass = 0.2;
  p.contacts.push_back(Finger(Vec3(0.03, 0, 0), Vec3(-1, 0, 0), 0.8));
  for (ConeModel cone : {ConeModel::kPyramid, ConeModel::kExact}) {
    const PlanResult r = SolveIpopt(p, Options(cone));
    // Torque balance already fails here (the weight does not pass through the
    // contact), or the cone does; either way it is a result.
    EXPECT_EQ(r.status, PlanStatus::kInfeasible) << r.message;
  }
  // Under the centre of mass but tilted 60 degrees: a unique equilibrium
  // whose tangential part exceeds mu = 0.5 times the normal part.
  PlanProblem tilted;
  tilted.object.mass = 0.2;
  const Vec3 n = Vec3(std::sin(1.05), 0, std::cos(1.05));
  tilted.contacts.push_back(Finger(Vec3::Zero(), n, 0.5));
  const PlanResult r = SolveIpopt(tilted, Options(ConeModel::kExact));
  EXPECT_EQ(r.status, PlanStatus::kInfeasible) << r.message;
  EXPECT_NE(r.message.find("unique"), std::string::npos) << r.message;
}

// kappa = 0: the exact cone lies between the inscribed pyramid (mu) and the
// circumscribed one (mu / cos(pi/k)), so do the optimal objectives.
TEST(IpoptSolver, ExactConeLiesBetweenThePyramids) {
  for (int contacts : {3, 4}) {
    const PlanProblem inner = ThreeFingerGrasp(contacts);
    const int k = 6;
    PlanProblem outer = inner;
    for (Contact& c : outer.contacts) c.friction /= std::cos(std::numbers::pi / k);
    const PlanResult exact = SolveIpopt(inner, Options(ConeModel::kExact, 0.0, k));
    const PlanResult pyramid = SolveIpopt(inner, Options(ConeModel::kPyramid, 0.0, k));
    const PlanResult circumscribed = SolveIpopt(outer, Options(ConeModel::kPyramid, 0.0, k));
    ASSERT_EQ(exact.status, PlanStatus::kOptimal) << exact.message;
    ASSERT_EQ(pyramid.status, PlanStatus::kOptimal) << pyramid.message;
    ASSERT_EQ(circumscribed.status, PlanStatus::kOptimal) << circumscribed.message;
    const double tol = 1e-7 * pyramid.objective;
    EXPECT_LE(exact.objective, pyramid.objective + tol);
    EXPECT_GE(exact.objective, circumscribed.objective - tol);
    EXPECT_LT(circumscribed.objective, pyramid.objective);  // the bracket is not empty
    EXPECT_LE(EquilibriumError(inner, Options(ConeModel::kExact), exact), 1e-8);
    EXPECT_GE(exact.min_margin, -1e-7);
  }
}

// With noisy sensors (kappa > 0) the exact plan keeps every force inside the
// robustly shrunk cone and costs more than the nominal plan.
TEST(IpoptSolver, RobustExactPlanKeepsItsMargin) {
  const PlanProblem noisy = ThreeFingerGrasp(4, 0.3);
  const PlanResult nominal = SolveIpopt(noisy, Options(ConeModel::kExact, 0.0));
  const PlanResult robust = SolveIpopt(noisy, Options(ConeModel::kExact, 2.0));
  ASSERT_EQ(nominal.status, PlanStatus::kOptimal) << nominal.message;
  ASSERT_EQ(robust.status, PlanStatus::kOptimal) << robust.message;
  EXPECT_GT(robust.objective, nominal.objective);
  EXPECT_GE(robust.min_margin, -1e-7);
  EXPECT_LE(EquilibriumError(noisy, Options(ConeModel::kExact), robust), 1e-8);
}

TEST(IpoptSolver, TimeLimitStopsTheSolveQuickly) {
  PlanOptions o = Options(ConeModel::kExact);
  o.ipopt.max_cpu_seconds = 1e-9;
  const auto start = std::chrono::steady_clock::now();
  const PlanResult r = SolveIpopt(ThreeFingerGrasp(4), o);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.status, PlanStatus::kSolverFailure);
  EXPECT_NE(r.message.find("time limit"), std::string::npos) << r.message;
  EXPECT_TRUE(r.forces.empty());
  EXPECT_LT(seconds, 0.5);
}

TEST(IpoptSolver, InterruptStopsTheSolve) {
  std::atomic<int> polls = 0;
  const PlanOptions o = Options(ConeModel::kPyramid);
  const SolveControl control{[&polls] { return ++polls >= 3; }};
  const PlanResult r = SolveIpopt(ThreeFingerGrasp(4), o, control);
  EXPECT_EQ(r.status, PlanStatus::kSolverFailure);
  EXPECT_EQ(r.message.rfind("interrupted", 0), 0u) << r.message;
  EXPECT_GE(polls.load(), 3);
}

TEST(IpoptSolver, PrintsNothingToStdout) {
  testing::internal::CaptureStdout();
  const PlanResult r = SolveIpopt(ThreeFingerGrasp(4), Options(ConeModel::kExact, 1.0));
  PlanProblem infeasible = Pinch(0.5, 0.05);
  for (Contact& c : infeasible.contacts) c.max_normal_force = 10.0;
  const PlanResult i = SolveIpopt(infeasible, Options(ConeModel::kExact));
  EXPECT_EQ(testing::internal::GetCapturedStdout(), "");
  EXPECT_EQ(r.status, PlanStatus::kOptimal);
  EXPECT_EQ(i.status, PlanStatus::kInfeasible);
}

// The server solves on several threads at once: concurrent solves with one
// shared solver object give bit-identical results to serial ones.
TEST(IpoptSolver, ConcurrentSolvesMatchSerialSolves) {
  const auto solver = MakeSolver(SolverKind::kIpopt);
  struct Case {
    PlanProblem problem;
    PlanOptions options;
  };
  std::vector<Case> cases = {
      {ThreeFingerGrasp(4, 0.2), Options(ConeModel::kPyramid, 1.0)},
      {ThreeFingerGrasp(3), Options(ConeModel::kExact, 0.0)},
      {ThreeFingerGrasp(4, 0.2), Options(ConeModel::kExact, 1.0)},
      {Pinch(0.5, 0.5), Options(ConeModel::kPyramid)},
  };
  std::vector<PlanResult> serial;
  for (const Case& c : cases) serial.push_back(*solver->Solve(c.problem, c.options));

  const int kThreads = 4;
  std::vector<std::vector<PlanResult>> parallel(kThreads);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      for (size_t k = 0; k < cases.size(); ++k) {
        const Case& c = cases[(k + t) % cases.size()];
        parallel[t].push_back(*solver->Solve(c.problem, c.options));
      }
    });
  }
  for (std::thread& t : threads) t.join();
  for (int t = 0; t < kThreads; ++t) {
    for (size_t k = 0; k < cases.size(); ++k) {
      const PlanResult& a = parallel[t][k];
      const PlanResult& b = serial[(k + t) % cases.size()];
      ASSERT_EQ(a.status, b.status);
      EXPECT_EQ(a.iterations, b.iterations);
      ASSERT_EQ(a.forces.size(), b.forces.size());
      for (size_t i = 0; i < a.forces.size(); ++i) EXPECT_EQ(a.forces[i], b.forces[i]);
    }
  }
}

}  // namespace
}  // namespace tactforce::planner
