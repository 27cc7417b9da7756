#include "tactforce/estimator/force_estimation.h"

#include <random>

#include <gtest/gtest.h>

#include "tactforce/planner/examples.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/solver.h"

namespace tactforce::estimator {
namespace {

using planner::Contact;
using planner::ContactKind;
using planner::PlanProblem;

PlanProblem Example(const std::string& name) {
  for (const auto& g : planner::BuiltInGrasps()) {
    if (g.name == name) return g.problem;
  }
  return {};
}

Eigen::VectorXd Stack(const std::vector<Vec3>& f) {
  Eigen::VectorXd out(3 * f.size());
  for (size_t i = 0; i < f.size(); ++i) out.segment<3>(3 * i) = f[i];
  return out;
}

TEST(Projection, EqualsTheClosestEquilibriumForce) {
  const PlanProblem p = Example("wrench-3f");
  const std::vector<double> readings = {2.1, 1.4, 3.9};
  absl::StatusOr<ForceEstimate> e = EstimateForces(p, readings);
  ASSERT_TRUE(e.ok()) << e.status();
  ASSERT_EQ(e->status, EstimateStatus::kOk);
  // Closed form, independently: min |f - f_m| s.t. G f = b via the KKT system.
  const auto eq = planner::ComputeForceEquilibrium(p, 1e-9);
  ASSERT_EQ(eq.rank, 6);
  Eigen::VectorXd fm = Eigen::VectorXd::Zero(9);
  for (int j = 0; j < 3; ++j) fm.segment<3>(3 * j) = readings[j] * p.contacts[j].normal;
  Eigen::MatrixXd kkt = Eigen::MatrixXd::Zero(15, 15);
  kkt.topLeftCorner(9, 9).setIdentity();
  kkt.topRightCorner(9, 6) = eq.grasp_matrix.transpose();
  kkt.bottomLeftCorner(6, 9) = eq.grasp_matrix;
  Eigen::VectorXd rhs(15);
  rhs << fm, eq.wrench;
  const Eigen::VectorXd sol = kkt.fullPivLu().solve(rhs);
  EXPECT_LE((Stack(e->forces) - sol.head(9)).cwiseAbs().maxCoeff(), 1e-10);
  for (int j = 0; j < 3; ++j) {
    EXPECT_NEAR(e->residuals[j], e->normal_forces[j] - readings[j], 1e-15);
  }
}

TEST(Projection, ConsistentReadingsAreReproduced) {
  // Readings taken from an equilibrium with purely normal forces come back.
  const PlanProblem p = Example("cylinder-4f");
  PlanProblem flat = p;
  flat.object.mass = 0.0;  // no weight: pure squeeze is an equilibrium
  const std::vector<double> readings = {2.0, 3.0, 2.0, 3.0};
  absl::StatusOr<ForceEstimate> e = EstimateForces(flat, readings);
  ASSERT_TRUE(e.ok());
  for (int j = 0; j < 4; ++j) EXPECT_NEAR(e->normal_forces[j], readings[j], 1e-12);
}

// Cube on a table (four extrinsic corner contacts) pushed down by one finger.
PlanProblem CubeOnTable(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(-1, 1);
  PlanProblem p;
  p.object.mass = 0.15 * (1 + 0.5 * u(rng));
  const double h = 0.04;
  p.object.com = Vec3(0.005 * u(rng), 0.005 * u(rng), 0.005 * u(rng));
  for (int k = 0; k < 4; ++k) {
    Contact c;
    c.kind = ContactKind::kExtrinsic;
    c.position = Vec3((k & 1 ? h : -h), (k & 2 ? h : -h), -h);
    c.normal = Vec3(0, 0, 1);
    c.friction = 0.6;
    p.contacts.push_back(c);
  }
  Contact finger;
  finger.position = Vec3(h * 0.5 * u(rng), h * 0.5 * u(rng), h);
  finger.normal = Vec3(0.2 * u(rng), 0.2 * u(rng), -1).normalized();
  finger.friction = 0.8;
  finger.sigma = 0.2;
  p.contacts.push_back(finger);
  return p;
}

TEST(Projection, ProblemTwoSatisfiesItsOptimalityConditions) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> reading(0.5, 4.0);
  for (int trial = 0; trial < 200; ++trial) {
    const PlanProblem p = CubeOnTable(rng);
    const double lambda = 1e-2;
    absl::StatusOr<ForceEstimate> e = EstimateForces(p, {reading(rng)});
    ASSERT_TRUE(e.ok()) << e.status();
    ASSERT_EQ(e->status, EstimateStatus::kOk);
    // Reconstruct the QP and check KKT: for the optimal x the best w >= 0 is
    // the nonnegative least-squares fit of the extrinsic normals, and the
    // x-gradient vanishes.
    const auto eq = planner::ComputeForceEquilibrium(p, 1e-9);
    const Eigen::VectorXd f = Stack(e->forces);
    EXPECT_LE((eq.grasp_matrix * f - eq.wrench).cwiseAbs().maxCoeff(), 1e-9);
    Eigen::VectorXd fm = Eigen::VectorXd::Zero(15);
    // w: with orthonormal, disjoint columns N_E, w = max(0, N_E^T (f - f_m)).
    Eigen::VectorXd nw = Eigen::VectorXd::Zero(15);
    // f_m: the finger's reading along its normal (reading = n.f - residual).
    const double finger_reading = e->normal_forces[4] - e->residuals[0];
    fm.segment<3>(12) = finger_reading * p.contacts[4].normal;
    for (int k = 0; k < 4; ++k) {
      const double wk =
          std::max(0.0, p.contacts[k].normal.dot(f.segment<3>(3 * k) - fm.segment<3>(3 * k)));
      nw.segment<3>(3 * k) = wk * p.contacts[k].normal;
    }
    const Eigen::VectorXd grad_x = eq.null_basis.transpose() * (2 * (f - fm - nw) + 2 * lambda * f);
    EXPECT_LE(grad_x.cwiseAbs().maxCoeff(), 1e-8) << "trial " << trial;
  }
}

TEST(NormalLsq, RecoversExactForcesFromNoiselessReadings) {
  // The pinch is determined by its two normal readings (one squeeze dof).
  const PlanProblem p = Example("sphere-pinch");
  absl::StatusOr<planner::PlanResult> truth =
      planner::Plan(p, planner::PlanOptions{}, planner::SolverKind::kGeometric);
  ASSERT_TRUE(truth.ok());
  std::vector<double> readings = truth->normal_forces;
  EstimateOptions o;
  o.method = EstimateMethod::kNormalLsq;
  o.origin_weight = 0.0;
  absl::StatusOr<ForceEstimate> e = EstimateForces(p, readings, o);
  ASSERT_TRUE(e.ok()) << e.status();
  ASSERT_EQ(e->status, EstimateStatus::kOk) << e->message;
  for (int i = 0; i < 2; ++i) {
    EXPECT_LE((e->forces[i] - truth->forces[i]).cwiseAbs().maxCoeff(), 1e-9);
  }
  // With the default small origin weight the bias stays tiny.
  o.origin_weight = 1e-2;
  e = EstimateForces(p, readings, o);
  ASSERT_TRUE(e.ok());
  for (int i = 0; i < 2; ++i) EXPECT_LE((e->forces[i] - truth->forces[i]).norm(), 1e-3);
}

TEST(NormalLsq, EstimatesStayInsideTheirCones) {
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0, 0.5);
  const PlanProblem p = Example("wrench-3f");
  EstimateOptions o;
  o.method = EstimateMethod::kNormalLsq;
  for (int trial = 0; trial < 100; ++trial) {
    std::vector<double> readings = {1 + noise(rng), 1 + noise(rng), 2 + noise(rng)};
    absl::StatusOr<ForceEstimate> e = EstimateForces(p, readings, o);
    ASSERT_TRUE(e.ok());
    if (e->status != EstimateStatus::kOk) continue;
    for (int i = 0; i < 3; ++i) {
      const Vec3& f = e->forces[i];
      const double fn = p.contacts[i].normal.dot(f);
      EXPECT_GE(fn, -1e-9);
      EXPECT_LE((f - fn * p.contacts[i].normal).norm(), p.contacts[i].friction * fn + 1e-9);
    }
  }
}

TEST(EstimateForces, BadInputNamesTheField) {
  const PlanProblem p = Example("wrench-3f");
  auto status = [&](const std::vector<double>& r, EstimateOptions o = {}) {
    return EstimateForces(p, r, o).status();
  };
  EXPECT_NE(status({1.0, 2.0}).message().find("readings: expected 3"), std::string::npos);
  EXPECT_NE(status({1.0, NAN, 2.0}).message().find("readings[1]"), std::string::npos);
  EstimateOptions bad;
  bad.origin_weight = -1;
  EXPECT_NE(status({1, 2, 3}, bad).message().find("origin_weight"), std::string::npos);
  PlanProblem broken = p;
  broken.contacts[1].normal.setZero();
  EXPECT_EQ(EstimateForces(broken, {1, 2, 3}).status().message().rfind("contacts[1].normal", 0),
            0u);
  // Negative readings are allowed but flagged.
  absl::StatusOr<ForceEstimate> e = EstimateForces(p, {1.0, -0.2, 2.0});
  ASSERT_TRUE(e.ok());
  EXPECT_EQ(e->negative_readings, std::vector<int>{1});
  EXPECT_NE(e->message.find("negative"), std::string::npos);
}

}  // namespace
}  // namespace tactforce::estimator
