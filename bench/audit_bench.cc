// Audit cost: one RunAudit on simulated press-release data with one or two
// hidden effects, for a few data sizes (samples at 200 Hz).
#include <benchmark/benchmark.h>

#include "tactforce/audit/audit.h"
#include "tactforce/sim/simulate.h"

namespace {

using namespace tactforce;

audit::MeasuredData MakeData(int samples, bool two_effects) {
  sim::SensorModel m;
  m.noise = 0.02;
  m.gain = -40;
  m.offset = 1000;
  m.effects.hysteresis_width = 0.15;
  if (two_effects) m.effects.delay = 0.03;
  sim::SimOptions o;
  o.rate = 200;
  o.seconds = samples / o.rate;
  o.seed = 9;
  auto run = sim::SimulateSensor(m, o);
  return *audit::ParseMeasuredCsv(sim::SimRunCsv(*run), "bench.csv");
}

void BM_Audit(benchmark::State& state) {
  const auto data = MakeData(static_cast<int>(state.range(0)), state.range(1) != 0);
  audit::AuditOptions opt;
  opt.downstream_gain = false;
  size_t causes = 0;
  for (auto _ : state) {
    auto rep = audit::RunAudit(data, opt);
    causes = rep.ok() ? rep->causes.size() : 0;
    benchmark::DoNotOptimize(causes);
  }
  state.counters["causes"] = static_cast<double>(causes);
}
BENCHMARK(BM_Audit)
    ->Args({1000, 0})
    ->Args({3000, 0})
    ->Args({3000, 1})
    ->Args({10000, 1})
    ->Unit(benchmark::kMillisecond);

void BM_Simulate(benchmark::State& state) {
  sim::SensorModel m;
  m.noise = 0.02;
  m.effects.lag = 0.02;
  m.effects.threshold = 0.2;
  sim::SimOptions o;
  o.seconds = 10;
  o.rate = 500;
  o.contact_radius = state.range(0) * 1e-3;
  for (auto _ : state) benchmark::DoNotOptimize(sim::SimulateSensor(m, o));
}
BENCHMARK(BM_Simulate)->Arg(0)->Arg(8)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
