// GEOMETRIC vs IPOPT on the same grasps, n = 2..6 contacts, same run.
//
//   build/bin/planner_bench [--benchmark_repetitions=5]
//
// After the Google Benchmark output it prints the speed ratio per n
// (median time per solve of IPOPT / GEOMETRIC).
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"

namespace tactforce::planner {
namespace {

// 64 feasible random grasps with exactly n contacts (fixed seed), so both
// backends see the same problems.
const std::vector<PlanProblem>& Grasps(int n) {
  static std::map<int, std::vector<PlanProblem>> cache;
  auto& out = cache[n];
  if (!out.empty()) return out;
  std::mt19937_64 rng(1000 + n);
  RandomGraspOptions ro;
  ro.min_contacts = ro.max_contacts = n;
  ro.infeasible_fraction = 0.0;
  const auto geometric = MakeSolver(SolverKind::kGeometric);
  while (out.size() < 64) {
    const RandomGrasp g = MakeRandomGrasp(rng, ro);
    absl::StatusOr<PlanResult> r = geometric->Solve(g.problem, PlanOptions{});
    if (r.ok() && r->status == PlanStatus::kOptimal) out.push_back(g.problem);
  }
  return out;
}

void BM_Plan(benchmark::State& state, SolverKind kind) {
  const int n = static_cast<int>(state.range(0));
  const auto& grasps = Grasps(n);
  const auto solver = MakeSolver(kind);
  const PlanOptions options;
  size_t i = 0;
  int failures = 0;
  for (auto _ : state) {
    absl::StatusOr<PlanResult> r = solver->Solve(grasps[i++ % grasps.size()], options);
    if (!r.ok() || r->status != PlanStatus::kOptimal) ++failures;
    benchmark::DoNotOptimize(r);
  }
  state.counters["contacts"] = n;
  state.counters["failures"] = failures;
}

void BM_Geometric(benchmark::State& s) { BM_Plan(s, SolverKind::kGeometric); }
void BM_Ipopt(benchmark::State& s) { BM_Plan(s, SolverKind::kIpopt); }
BENCHMARK(BM_Geometric)->DenseRange(2, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Ipopt)->DenseRange(2, 6)->Unit(benchmark::kMicrosecond);

// Console output as usual, plus the per-n times for the ratio table.
class RatioReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& run : runs) {
      if (run.error_occurred) continue;
      // Single runs, or the median aggregate when repeated.
      if (run.run_type == Run::RT_Aggregate && run.aggregate_name != "median") continue;
      const std::string name = run.run_name.function_name;
      const int n = std::stoi(run.run_name.args);
      (name == "BM_Geometric" ? geometric_ : ipopt_)[n] = run.GetAdjustedRealTime();
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf("\n| contacts | geometric (us) | ipopt (us) | ipopt / geometric |\n");
    std::printf("|---:|---:|---:|---:|\n");
    for (const auto& [n, g] : geometric_) {
      if (!ipopt_.count(n)) continue;
      std::printf("| %d | %.1f | %.1f | %.0fx |\n", n, g, ipopt_[n], ipopt_[n] / g);
    }
  }

 private:
  std::map<int, double> geometric_, ipopt_;
};

}  // namespace
}  // namespace tactforce::planner

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  tactforce::planner::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
