// Closed-loop grasp trials in MuJoCo (issue 7): wall time per trial and the
// real-time factor (simulated seconds per wall second, counter
// `x_realtime`), per object and feedback mode. The raw-feedback rows are the
// baseline for the estimated ones in the same run: their ratio is the cost
// of estimating forces inside the 200 Hz loop.
//   build/bin/experiment_bench --benchmark_min_time=2
#include <benchmark/benchmark.h>

#include "tactforce/experiment/grasp.h"

namespace {

using tactforce::experiment::Feedback;
using tactforce::experiment::GraspConfig;
using tactforce::experiment::GraspObject;
using tactforce::experiment::GraspSetup;

void BM_GraspTrial(benchmark::State& state, GraspObject object, Feedback feedback) {
  GraspConfig c;
  c.object = object;
  c.feedback = feedback;
  auto setup = GraspSetup::Create(c);
  if (!setup.ok()) {
    state.SkipWithError(std::string(setup.status().message()).c_str());
    return;
  }
  int trial = 0;
  double sim = 0, wall = 0;
  for (auto _ : state) {
    auto r = tactforce::experiment::RunGraspTrial(**setup, trial++);
    if (!r.ok()) {
      state.SkipWithError(std::string(r.status().message()).c_str());
      return;
    }
    sim += r->sim_seconds;
    wall += r->wall_seconds;
  }
  state.counters["x_realtime"] = wall > 0 ? sim / wall : 0.0;
  state.counters["sim_s_per_trial"] = trial > 0 ? sim / trial : 0.0;
}

#define TACTFORCE_GRASP_BENCH(object, name)                                                     \
  BENCHMARK_CAPTURE(BM_GraspTrial, name##_raw, GraspObject::object, Feedback::kRaw)             \
      ->Unit(benchmark::kMillisecond);                                                          \
  BENCHMARK_CAPTURE(BM_GraspTrial, name##_estimated, GraspObject::object, Feedback::kEstimated) \
      ->Unit(benchmark::kMillisecond)

TACTFORCE_GRASP_BENCH(kSphere, sphere);
TACTFORCE_GRASP_BENCH(kWrench, wrench);
TACTFORCE_GRASP_BENCH(kCylinder, cylinder);
TACTFORCE_GRASP_BENCH(kCube, cube);

}  // namespace

BENCHMARK_MAIN();
