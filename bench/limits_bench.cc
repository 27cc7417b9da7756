// The largest requests tactforce-server accepts with its default limits
// (64 contacts, 64 cone sides, --max-trajectory-work 4,000,000), timed
// through the same api:: handlers the server runs, so the README can say
// how long the worst accepted call takes and that --solve-timeout-ms
// (default 10 s) bounds the rest:
//
//   build/bin/limits_bench [--benchmark_repetitions=3]
//
// Rows: Plan of 64 random contacts with GEOMETRIC (k = 12 and 64), IPOPT
// with the pyramid and with the EXACT circular cone, CROSS_CHECK; a
// trajectory of 64 contacts at the work limit (k = 12: 5,208 steps), cut by
// a 10 s work budget as the server would.
#include <benchmark/benchmark.h>

#include <random>

#include "tactforce/api/convert.h"
#include "tactforce/api/dispatch.h"
#include "tactforce/api/services.h"
#include "tactforce/planner/random_grasps.h"

namespace tactforce::api {
namespace {

constexpr int kContacts = 64;

// One fixed 64-contact random grasp (feasibility not required: the cost of
// an accepted request is what is measured).
v1::PlanRequest LargestRequest(planner::SolverKind solver, planner::ConeModel cone,
                               int cone_sides) {
  std::mt19937_64 rng(64);
  planner::RandomGraspOptions ro;
  ro.min_contacts = ro.max_contacts = kContacts;
  const planner::RandomGrasp g = planner::MakeRandomGrasp(rng, ro);
  planner::PlanOptions options;
  options.cone = cone;
  options.cone_sides = cone_sides;
  return ToRequest(g.problem, options, solver);
}

void RunPlan(benchmark::State& state, planner::SolverKind solver, planner::ConeModel cone,
             int sides) {
  const v1::PlanRequest request = LargestRequest(solver, cone, sides);
  CallLimits limits;
  limits.solve_timeout_ms = 10'000;  // the server's default --solve-timeout-ms
  for (auto _ : state) {
    absl::StatusOr<v1::PlanResponse> r = HandlePlan(request, limits);
    if (!r.ok()) state.SkipWithError(std::string(r.status().message()).c_str());
    state.counters["optimal"] = r.ok() && r->status() == v1::PLAN_STATUS_OPTIMAL;
    benchmark::DoNotOptimize(r);
  }
}

void BM_Plan64_Geometric_k12(benchmark::State& s) {
  RunPlan(s, planner::SolverKind::kGeometric, planner::ConeModel::kPyramid, 12);
}
void BM_Plan64_Geometric_k64(benchmark::State& s) {
  RunPlan(s, planner::SolverKind::kGeometric, planner::ConeModel::kPyramid, 64);
}
void BM_Plan64_Ipopt_Pyramid_k12(benchmark::State& s) {
  RunPlan(s, planner::SolverKind::kIpopt, planner::ConeModel::kPyramid, 12);
}
void BM_Plan64_Ipopt_Exact(benchmark::State& s) {
  RunPlan(s, planner::SolverKind::kIpopt, planner::ConeModel::kExact, 12);
}
void BM_Plan64_CrossCheck_k64(benchmark::State& s) {
  RunPlan(s, planner::SolverKind::kCrossCheck, planner::ConeModel::kPyramid, 64);
}

// A trajectory at the work limit, under the server's default 10 s budget.
void BM_Trajectory64_AtWorkLimit(benchmark::State& state) {
  v1::TrajectoryRequest request;
  *request.mutable_plan() =
      LargestRequest(planner::SolverKind::kGeometric, planner::ConeModel::kPyramid, 12);
  v1::Inertia* inertia = request.mutable_plan()->mutable_object()->mutable_inertia();
  inertia->set_ixx(1e-3);
  inertia->set_iyy(1e-3);
  inertia->set_izz(1e-3);
  const int steps = static_cast<int>(CallLimits{}.max_trajectory_work / (kContacts * 12));
  for (int k = 0; k < steps; ++k) request.add_steps()->mutable_gravity()->set_z(-9.81);
  for (auto _ : state) {
    const WorkBudget budget(10.0, nullptr);
    const CallState call_state{budget.Interrupt()};
    absl::StatusOr<v1::TrajectoryResponse> r = HandleTrajectory(request, CallLimits{}, call_state);
    const absl::Status status = r.ok() ? absl::OkStatus() : budget.Explain(r.status());
    state.counters["stopped_by_budget"] = status.code() == absl::StatusCode::kResourceExhausted;
    state.counters["steps"] = steps;
    benchmark::DoNotOptimize(r);
  }
}

BENCHMARK(BM_Plan64_Geometric_k12)->Unit(benchmark::kMillisecond)->Iterations(5);
BENCHMARK(BM_Plan64_Geometric_k64)->Unit(benchmark::kMillisecond)->Iterations(3);
BENCHMARK(BM_Plan64_Ipopt_Pyramid_k12)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Plan64_Ipopt_Exact)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Plan64_CrossCheck_k64)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_Trajectory64_AtWorkLimit)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace
}  // namespace tactforce::api

BENCHMARK_MAIN();
