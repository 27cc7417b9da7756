// EstimationWorkspace: warm PROJECTION (with and without extrinsic
// contacts) and NORMAL_LSQ estimates allocate nothing, and a workspace
// reused across problems answers as fresh estimates do.
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "support/allocation_counter.h"
#include "tactforce/estimator/force_estimation.h"
#include "tactforce/planner/random_grasps.h"

namespace tactforce::estimator {
namespace {

struct Case {
  planner::PlanProblem problem;
  std::vector<double> readings;
};

// Seeded random grasps (some with extrinsic contacts) and noisy readings.
std::vector<Case> Cases(int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 0.3);
  planner::RandomGraspOptions ro;
  ro.infeasible_fraction = 0.0;
  ro.extrinsic_probability = 0.3;
  std::vector<Case> out;
  while (static_cast<int>(out.size()) < count) {
    Case c{planner::MakeRandomGrasp(rng, ro).problem, {}};
    for (const planner::Contact& contact : c.problem.contacts) {
      if (contact.kind == planner::ContactKind::kIntrinsic) c.readings.push_back(2.0 + noise(rng));
    }
    out.push_back(std::move(c));
  }
  return out;
}

void ExpectSame(const ForceEstimate& a, const ForceEstimate& b) {
  ASSERT_EQ(a.status, b.status);
  ASSERT_EQ(a.forces.size(), b.forces.size());
  for (size_t i = 0; i < a.forces.size(); ++i) EXPECT_EQ(a.forces[i], b.forces[i]);
  EXPECT_EQ(a.residuals, b.residuals);
  EXPECT_EQ(a.message, b.message);
  EXPECT_EQ(a.iterations, b.iterations);
}

TEST(EstimationWorkspace, WarmEstimatesAllocateNothing) {
  const std::vector<Case> cases = Cases(40, 11);
  int with_extrinsic = 0;
  for (const Case& c : cases) {
    for (const auto& contact : c.problem.contacts) {
      if (contact.kind == planner::ContactKind::kExtrinsic) {
        ++with_extrinsic;
        break;
      }
    }
  }
  ASSERT_GT(with_extrinsic, 0);
  for (EstimateMethod method : {EstimateMethod::kProjection, EstimateMethod::kNormalLsq}) {
    EstimateOptions options;
    options.method = method;
    EstimationWorkspace workspace;
    ForceEstimate out;
    // Warm-up; messages (infeasible grasps, negative readings) allocate, so
    // only estimates that end OK without one are counted.
    std::vector<const Case*> quiet;
    for (const Case& c : cases) {
      ASSERT_TRUE(EstimateForces(c.problem, c.readings, options, &workspace, &out).ok());
      if (out.status == EstimateStatus::kOk && out.message.empty()) quiet.push_back(&c);
    }
    ASSERT_GE(quiet.size(), 30u) << ToString(method);
    const long before = tactforce::testing::AllocationCount();
    int ok = 0;
    tactforce::testing::ArmAllocationTrap(true);
    for (int round = 0; round < 2; ++round) {
      for (const Case* c : quiet) {
        ASSERT_TRUE(EstimateForces(c->problem, c->readings, options, &workspace, &out).ok());
        ok += out.status == EstimateStatus::kOk ? 1 : 0;
      }
    }
    tactforce::testing::ArmAllocationTrap(false);
    EXPECT_EQ(tactforce::testing::AllocationCount() - before, 0) << ToString(method);
    EXPECT_EQ(ok, 2 * static_cast<int>(quiet.size())) << ToString(method);
  }
}

TEST(EstimationWorkspace, ReusedWorkspaceAnswersAsFreshEstimates) {
  const std::vector<Case> cases = Cases(200, 12);
  EstimationWorkspace workspace;
  ForceEstimate reused;
  for (size_t k = 0; k < cases.size(); ++k) {
    EstimateOptions options;
    options.method = k % 2 ? EstimateMethod::kNormalLsq : EstimateMethod::kProjection;
    absl::StatusOr<ForceEstimate> fresh =
        EstimateForces(cases[k].problem, cases[k].readings, options);
    const absl::Status s =
        EstimateForces(cases[k].problem, cases[k].readings, options, &workspace, &reused);
    ASSERT_EQ(s.ok(), fresh.ok()) << k;
    if (s.ok()) ExpectSame(reused, *fresh);
  }
  // A bad request names its field and leaves the workspace usable.
  std::vector<double> short_readings = cases[0].readings;
  short_readings.pop_back();
  const absl::Status bad =
      EstimateForces(cases[0].problem, short_readings, {}, &workspace, &reused);
  EXPECT_NE(bad.message().find("readings: expected"), std::string::npos) << bad;
  ASSERT_TRUE(EstimateForces(cases[1].problem, cases[1].readings, {}, &workspace, &reused).ok());
  ExpectSame(reused, *EstimateForces(cases[1].problem, cases[1].readings, {}));
}

}  // namespace
}  // namespace tactforce::estimator
