// Cost of the parameter tightening (issue 28): the same 4-contact GEOMETRIC
// workspace solves as planner_bench's, without and with an inertial-parameter
// covariance (mass 5 %, CoM 3 mm, inertia 10 % of m r^2, correlated).
//   uncertainty_bench [SOLVES] [CONTACTS]   wall time per solve, both ways
// Instructions: count the two out-of-line functions under callgrind,
//   valgrind --tool=callgrind --toggle-collect='*TimedPlainSolve*' build/bin/uncertainty_bench 640
//   4 valgrind --tool=callgrind --toggle-collect='*TimedUncertainSolve*'
//   build/bin/uncertainty_bench 640 4
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/workspace.h"

namespace tactforce::planner {
namespace {

Matrix10d BenchCovariance(std::mt19937_64& rng, double mass) {
  std::normal_distribution<double> normal;
  Eigen::Matrix<double, 10, 1> scale;
  scale << 0.05 * mass, Eigen::Vector3d::Constant(0.003 * mass),
      Eigen::Matrix<double, 6, 1>::Constant(0.1 * mass * 0.05 * 0.05);
  Matrix10d a;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) a(i, j) = normal(rng);
  return scale.asDiagonal() * (a * a.transpose() / 10.0) * scale.asDiagonal();
}

// Pairs (plain, uncertain) of n-contact grasps that are feasible both ways
// (planner_bench's seed), so neither side pays for an infeasibility report.
void Grasps(int n, std::vector<PlanProblem>* plain, std::vector<PlanProblem>* uncertain) {
  std::mt19937_64 rng(1000 + n);
  RandomGraspOptions ro;
  ro.min_contacts = ro.max_contacts = n;
  ro.infeasible_fraction = 0.0;
  while (plain->size() < 64) {
    PlanProblem p = MakeRandomGrasp(rng, ro).problem;
    PlanProblem u = p;
    u.object.uncertainty.covariance = BenchCovariance(rng, p.object.mass);
    absl::StatusOr<PlanResult> a = Plan(p, PlanOptions{}, SolverKind::kGeometric);
    absl::StatusOr<PlanResult> b = Plan(u, PlanOptions{}, SolverKind::kGeometric);
    if (a.ok() && b.ok() && a->status == PlanStatus::kOptimal &&
        b->status == PlanStatus::kOptimal) {
      plain->push_back(p);
      uncertain->push_back(u);
    }
  }
}

[[gnu::noinline]] bool TimedPlainSolve(const PlanProblem& p, PlanningWorkspace* w, PlanResult* r) {
  return Plan(p, PlanOptions{}, SolverKind::kGeometric, w, r).ok();
}

[[gnu::noinline]] bool TimedUncertainSolve(const PlanProblem& p, PlanningWorkspace* w,
                                           PlanResult* r) {
  return Plan(p, PlanOptions{}, SolverKind::kGeometric, w, r).ok();
}

template <typename Solve>
double MicrosecondsPerSolve(const std::vector<PlanProblem>& grasps, int solves, Solve solve) {
  PlanningWorkspace workspace;
  PlanResult result;
  for (const PlanProblem& p : grasps) solve(p, &workspace, &result);  // warm-up
  const auto start = std::chrono::steady_clock::now();
  for (int i = 0; i < solves; ++i) solve(grasps[i % grasps.size()], &workspace, &result);
  return std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start)
             .count() /
         solves;
}

}  // namespace
}  // namespace tactforce::planner

int main(int argc, char** argv) {
  using namespace tactforce::planner;
  const int solves = argc > 1 ? std::atoi(argv[1]) : 640;
  const int contacts = argc > 2 ? std::atoi(argv[2]) : 4;
  std::vector<PlanProblem> plain, uncertain;
  Grasps(contacts, &plain, &uncertain);
  const double a = MicrosecondsPerSolve(plain, solves, TimedPlainSolve);
  const double b = MicrosecondsPerSolve(uncertain, solves, TimedUncertainSolve);
  std::printf(
      "%d contacts, %d solves each: plain %.2f us, with parameter covariance %.2f us (%+.0f %%)\n",
      contacts, solves, a, b, 100.0 * (b / a - 1.0));
  return 0;
}
