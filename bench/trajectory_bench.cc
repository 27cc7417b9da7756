// GeoDEx Table II: the 3-finger wrench grasp lifted and rotated over 100 and
// 300 steps, GEOMETRIC (warm and cold) vs IPOPT, in the same run.
//
//   build/bin/trajectory_bench
//
// Prints Google Benchmark's table and then total / per-step times and ratios.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <string>

#include "tactforce/planner/examples.h"
#include "tactforce/planner/trajectory.h"

namespace tactforce::planner {
namespace {

void BM_Trajectory(benchmark::State& state, SolverKind kind, bool warm) {
  const int steps = static_cast<int>(state.range(0));
  const TrajectoryProblem t = WrenchLiftAndRotate(steps);
  int optimal = 0;
  for (auto _ : state) {
    absl::StatusOr<TrajectoryResult> r = PlanTrajectory(t, PlanOptions{}, kind, warm);
    optimal = r.ok() ? r->optimal : -1;
    benchmark::DoNotOptimize(r);
  }
  state.counters["steps"] = steps;
  state.counters["optimal_steps"] = optimal;
}

void BM_GeometricWarm(benchmark::State& s) { BM_Trajectory(s, SolverKind::kGeometric, true); }
void BM_GeometricCold(benchmark::State& s) { BM_Trajectory(s, SolverKind::kGeometric, false); }
void BM_Ipopt(benchmark::State& s) { BM_Trajectory(s, SolverKind::kIpopt, false); }
BENCHMARK(BM_GeometricWarm)->Arg(100)->Arg(300)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_GeometricCold)->Arg(100)->Arg(300)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Ipopt)->Arg(100)->Arg(300)->Unit(benchmark::kMillisecond)->Iterations(3);

class TableReporter : public benchmark::ConsoleReporter {
 public:
  void ReportRuns(const std::vector<Run>& runs) override {
    ConsoleReporter::ReportRuns(runs);
    for (const Run& r : runs) {
      if (r.error_occurred) continue;
      if (r.run_type == Run::RT_Aggregate && r.aggregate_name != "median") continue;
      times_[r.run_name.function_name][std::stoi(r.run_name.args)] = r.GetAdjustedRealTime();  // ms
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf(
        "\n| steps | IPOPT total (ms) | geometric warm (ms) | geometric cold (ms) | per step IPOPT "
        "/ warm (us) | IPOPT / warm | cold / warm |\n");
    std::printf("|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const auto& [steps, warm] : times_["BM_GeometricWarm"]) {
      const double ipopt = times_["BM_Ipopt"][steps], cold = times_["BM_GeometricCold"][steps];
      std::printf("| %d | %.1f | %.2f | %.2f | %.0f / %.1f | %.0fx | %.2fx |\n", steps, ipopt, warm,
                  cold, 1e3 * ipopt / steps, 1e3 * warm / steps, ipopt / warm, cold / warm);
    }
    std::printf(
        "\nGeoDEx Table II (paper): SOCP 4.81 s / 13.36 s vs geometric 0.31 s / 0.97 s (about "
        "14x).\n");
  }

 private:
  std::map<std::string, std::map<int, double>> times_;
};

}  // namespace
}  // namespace tactforce::planner

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  tactforce::planner::TableReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
