// PlanningWorkspace: a warm GEOMETRIC solve allocates nothing (global
// operator new is replaced by support/allocation_counter.cc and counts), a workspace reused across
// grasps of different sizes answers as fresh solves do, and workspaces on
// 8 threads answer as the serial run does.
#include "tactforce/planner/workspace.h"

#include <random>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "support/allocation_counter.h"
#include "tactforce/planner/examples.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/trajectory.h"

namespace tactforce::planner {
namespace {

// Feasible random grasps with n contacts (fixed seed), as in planner_bench.
std::vector<PlanProblem> Grasps(int n, int count, uint64_t seed) {
  std::mt19937_64 rng(seed);
  RandomGraspOptions ro;
  ro.min_contacts = ro.max_contacts = n;
  ro.infeasible_fraction = 0.0;
  std::vector<PlanProblem> out;
  const auto solver = MakeSolver(SolverKind::kGeometric);
  while (static_cast<int>(out.size()) < count) {
    RandomGrasp g = MakeRandomGrasp(rng, ro);
    absl::StatusOr<PlanResult> r = solver->Solve(g.problem, PlanOptions{});
    if (r.ok() && r->status == PlanStatus::kOptimal) out.push_back(std::move(g.problem));
  }
  return out;
}

void ExpectSameAnswer(const PlanResult& a, const PlanResult& b) {
  ASSERT_EQ(a.status, b.status);
  ASSERT_EQ(a.forces.size(), b.forces.size());
  for (size_t i = 0; i < a.forces.size(); ++i) {
    EXPECT_EQ(a.forces[i], b.forces[i]) << "contact " << i;
  }
  EXPECT_EQ(a.normal_force_sigma, b.normal_force_sigma);
  EXPECT_EQ(a.min_margin, b.min_margin);
  EXPECT_EQ(a.objective, b.objective);
  EXPECT_EQ(a.geometric.active_set, b.geometric.active_set);
  EXPECT_EQ(a.message, b.message);
}

TEST(PlanningWorkspace, WarmGeometricSolvesAllocateNothing) {
  const auto solver = MakeSolver(SolverKind::kGeometric);
  for (int n : {2, 3, 4, 6}) {
    const std::vector<PlanProblem> grasps = Grasps(n, 20, 500 + n);
    PlanningWorkspace workspace;
    PlanResult result;
    PlanOptions options;
    // Warm-up: the workspace grows to the largest active set of these grasps.
    for (const PlanProblem& p : grasps) {
      ASSERT_TRUE(solver->Solve(p, options, &workspace, &result).ok());
    }
    const long before = tactforce::testing::AllocationCount();
    tactforce::testing::ArmAllocationTrap(true);
    int optimal = 0;
    for (int round = 0; round < 3; ++round) {
      for (const PlanProblem& p : grasps) {
        ASSERT_TRUE(solver->Solve(p, options, &workspace, &result).ok());
        optimal += result.status == PlanStatus::kOptimal ? 1 : 0;
      }
    }
    tactforce::testing::ArmAllocationTrap(false);
    EXPECT_EQ(tactforce::testing::AllocationCount() - before, 0) << n << " contacts";
    EXPECT_EQ(optimal, 60);
    // Warm-started like PlanStream: the previous answer's active set.
    std::vector<int> previous = result.geometric.active_set;
    previous.reserve(64);
    options.warm_start.reserve(64);
    const long warm_before = tactforce::testing::AllocationCount();
    tactforce::testing::ArmAllocationTrap(true);
    for (const PlanProblem& p : grasps) {
      options.warm_start.assign(previous.begin(), previous.end());
      ASSERT_TRUE(solver->Solve(p, options, &workspace, &result).ok());
      previous.assign(result.geometric.active_set.begin(), result.geometric.active_set.end());
    }
    tactforce::testing::ArmAllocationTrap(false);
    EXPECT_EQ(tactforce::testing::AllocationCount() - warm_before, 0)
        << n << " contacts, warm-started";
  }
}

TEST(PlanningWorkspace, CountsAllocationsAtAll) {
  // The counter is live: a cold solve does allocate.
  const auto solver = MakeSolver(SolverKind::kGeometric);
  const PlanProblem p = Grasps(4, 1, 77)[0];
  const long before = tactforce::testing::AllocationCount();
  PlanningWorkspace workspace;
  PlanResult result;
  ASSERT_TRUE(solver->Solve(p, PlanOptions{}, &workspace, &result).ok());
  EXPECT_GT(tactforce::testing::AllocationCount() - before, 0);
}

TEST(PlanningWorkspace, ReuseAcrossSizesAnswersAsFreshSolves) {
  const auto solver = MakeSolver(SolverKind::kGeometric);
  std::mt19937_64 rng(91);
  RandomGraspOptions ro;  // 2..6 contacts, some infeasible on purpose
  ro.infeasible_fraction = 0.2;
  PlanningWorkspace workspace;
  PlanResult reused;
  int infeasible = 0;
  for (int k = 0; k < 300; ++k) {
    const RandomGrasp g = MakeRandomGrasp(rng, ro);
    PlanOptions options;
    options.cone_sides = 4 + k % 9;
    options.confidence = (k % 4) * 0.5;
    absl::StatusOr<PlanResult> fresh = solver->Solve(g.problem, options);
    absl::Status s = solver->Solve(g.problem, options, &workspace, &reused);
    ASSERT_EQ(s.ok(), fresh.ok()) << k;
    if (!s.ok()) continue;
    infeasible += reused.status == PlanStatus::kInfeasible ? 1 : 0;
    ExpectSameAnswer(reused, *fresh);
  }
  EXPECT_GT(infeasible, 0);  // the mix did exercise infeasible answers
  // Invalid requests leave the workspace usable.
  PlanProblem bad = Grasps(3, 1, 5)[0];
  bad.contacts[1].normal = Vec3::Zero();
  EXPECT_FALSE(solver->Solve(bad, PlanOptions{}, &workspace, &reused).ok());
  const PlanProblem good = Grasps(3, 1, 6)[0];
  ASSERT_TRUE(solver->Solve(good, PlanOptions{}, &workspace, &reused).ok());
  ExpectSameAnswer(reused, *solver->Solve(good, PlanOptions{}));
}

TEST(PlanningWorkspace, EightThreadsAnswerAsTheSerialRun) {
  const auto solver = MakeSolver(SolverKind::kGeometric);
  std::vector<PlanProblem> grasps;
  for (int n = 2; n <= 6; ++n) {
    for (PlanProblem& p : Grasps(n, 50, 300 + n)) grasps.push_back(std::move(p));
  }
  constexpr int kSolves = 10000;
  constexpr int kThreads = 8;
  std::vector<PlanResult> serial(kSolves);
  {
    PlanningWorkspace workspace;
    for (int k = 0; k < kSolves; ++k) {
      ASSERT_TRUE(
          solver->Solve(grasps[k % grasps.size()], PlanOptions{}, &workspace, &serial[k]).ok());
    }
  }
  std::vector<PlanResult> parallel(kSolves);
  std::vector<std::thread> threads;
  for (int t = 0; t < kThreads; ++t) {
    threads.emplace_back([&, t] {
      PlanningWorkspace workspace;
      for (int k = t; k < kSolves; k += kThreads) {
        if (!solver->Solve(grasps[k % grasps.size()], PlanOptions{}, &workspace, &parallel[k])
                 .ok()) {
          parallel[k].status = PlanStatus::kSolverFailure;
        }
      }
    });
  }
  for (std::thread& th : threads) th.join();
  for (int k = 0; k < kSolves; ++k) {
    ASSERT_EQ(parallel[k].status, PlanStatus::kOptimal) << k;
    ExpectSameAnswer(parallel[k], serial[k]);
    if (::testing::Test::HasFailure()) FAIL() << "solve " << k;
  }
}

TEST(PlanningWorkspace, TrajectoryReusesOneWorkspace) {
  // The trajectory path runs through one workspace; its steps equal
  // independent solves of the same step problems (cold, so compare forces).
  const TrajectoryProblem t = WrenchLiftAndRotate(40);
  absl::StatusOr<TrajectoryResult> r =
      PlanTrajectory(t, PlanOptions{}, SolverKind::kGeometric, /*warm_start=*/false);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_EQ(r->steps.size(), 40u);
  EXPECT_EQ(r->optimal, 40);
  absl::StatusOr<TrajectoryResult> warm =
      PlanTrajectory(t, PlanOptions{}, SolverKind::kGeometric, /*warm_start=*/true);
  ASSERT_TRUE(warm.ok());
  for (size_t i = 0; i < r->steps.size(); ++i) {
    ASSERT_EQ(warm->steps[i].forces.size(), r->steps[i].forces.size());
    for (size_t c = 0; c < r->steps[i].forces.size(); ++c) {
      EXPECT_LE((warm->steps[i].forces[c] - r->steps[i].forces[c]).norm(), 1e-9);
    }
  }
}

}  // namespace
}  // namespace tactforce::planner
