// GEOMETRIC vs IPOPT on the same grasps, n = 2..6 contacts, same run.
//
//   build/bin/planner_bench [--benchmark_repetitions=5]
//
// Rows per n:
//   BM_Geometric   ForceSolver::Solve(problem, options): a fresh result and
//                  workspace per call (the one-off API)
//   BM_Workspace   the in-place Solve with one PlanningWorkspace and
//                  PlanResult (what the server, PlanStream, trajectories use)
//   BM_QpOnly      only the dense QP of the same grasps (SolveDenseQp in
//                  place), so the cost of preparation stays visible; the
//                  table's "QP / workspace" is that split
//   BM_Ipopt       the Ipopt SOCP reference
// Counters: allocs = heap allocations per solve (operator new is counted in
// this binary), qp_iter = active-set iterations (additions and drops) per
// workspace solve, instr = user-space instructions per solve from
// perf_event_open (n/a where the kernel refuses it; then see
// scripts/count_instructions.sh).
// After the Google Benchmark output it prints the table of medians.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "instruction_counter.h"
#include "spdlog/spdlog.h"
#include "support/allocation_counter.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/dispatch.h"
#include "tactforce/planner/dense_qp.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/workspace.h"

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

// Per-iteration counters measured over the timed loop.
class Counters {
 public:
  void Start() {
    allocations_ = tactforce::testing::AllocationCount();
    instructions_ = counter_.Read();
  }
  void Stop(benchmark::State& state, int n) {
    const double iterations = static_cast<double>(state.iterations());
    state.counters["contacts"] = n;
    state.counters["allocs"] = (tactforce::testing::AllocationCount() - allocations_) / iterations;
    if (counter_.available()) {
      state.counters["instr"] = (counter_.Read() - instructions_) / iterations;
    }
  }

 private:
  bench::InstructionCounter counter_;
  long allocations_ = 0;
  uint64_t instructions_ = 0;
};

void BM_Plan(benchmark::State& state, SolverKind kind) {
  const int n = static_cast<int>(state.range(0));
  const auto& grasps = Grasps(n);
  const auto solver = MakeSolver(kind);
  const PlanOptions options;
  size_t i = 0;
  int failures = 0;
  Counters counters;
  counters.Start();
  for (auto _ : state) {
    absl::StatusOr<PlanResult> r = solver->Solve(grasps[i++ % grasps.size()], options);
    if (!r.ok() || r->status != PlanStatus::kOptimal) ++failures;
    benchmark::DoNotOptimize(r);
  }
  counters.Stop(state, n);
  state.counters["failures"] = failures;
}

// The timed call of BM_Workspace, kept out of line so that callgrind can
// count exactly it: --toggle-collect='*TimedWorkspaceSolve*'.
[[gnu::noinline]] bool TimedWorkspaceSolve(const ForceSolver& solver, const PlanProblem& problem,
                                           const PlanOptions& options, PlanningWorkspace* workspace,
                                           PlanResult* result) {
  return solver.Solve(problem, options, workspace, result).ok() &&
         result->status == PlanStatus::kOptimal;
}

void BM_Workspace(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto& grasps = Grasps(n);
  const auto solver = MakeSolver(SolverKind::kGeometric);
  const PlanOptions options;
  PlanningWorkspace workspace;
  PlanResult result;
  for (const PlanProblem& p : grasps) (void)solver->Solve(p, options, &workspace, &result);
  size_t i = 0;
  int failures = 0;
  int64_t qp_iterations = 0;
  Counters counters;
  counters.Start();
  for (auto _ : state) {
    if (!TimedWorkspaceSolve(*solver, grasps[i++ % grasps.size()], options, &workspace, &result)) {
      ++failures;
    }
    qp_iterations += result.iterations;
    benchmark::DoNotOptimize(result);
  }
  counters.Stop(state, n);
  state.counters["qp_iter"] = static_cast<double>(qp_iterations) / state.iterations();
  state.counters["failures"] = failures;
}

// The FE-plane QPs the geometric backend solved for these grasps.
const std::vector<DenseQp>& PlaneQps(int n) {
  static std::map<int, std::vector<DenseQp>> cache;
  auto& out = cache[n];
  if (!out.empty()) return out;
  const auto solver = MakeSolver(SolverKind::kGeometric);
  PlanningWorkspace workspace;
  PlanResult result;
  for (const PlanProblem& p : Grasps(n)) {
    if (solver->Solve(p, PlanOptions{}, &workspace, &result).ok()) out.push_back(workspace.qp);
  }
  return out;
}

// The timed call of BM_QpOnly, out of line for callgrind as above.
[[gnu::noinline]] bool TimedQpSolve(const DenseQp& qp, DenseQpWorkspace* workspace,
                                    DenseQpResult* result) {
  SolveDenseQp(qp, {}, workspace, result);
  return result->status == DenseQpStatus::kOptimal;
}

void BM_QpOnly(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto& qps = PlaneQps(n);
  DenseQpWorkspace workspace;
  DenseQpResult result;
  for (const DenseQp& qp : qps) SolveDenseQp(qp, {}, &workspace, &result);
  size_t i = 0;
  int failures = 0;
  Counters counters;
  counters.Start();
  for (auto _ : state) {
    if (!TimedQpSolve(qps[i++ % qps.size()], &workspace, &result)) ++failures;
    benchmark::DoNotOptimize(result);
  }
  counters.Stop(state, n);
  state.counters["failures"] = failures;
}

void BM_Geometric(benchmark::State& s) { BM_Plan(s, SolverKind::kGeometric); }
void BM_Ipopt(benchmark::State& s) { BM_Plan(s, SolverKind::kIpopt); }
BENCHMARK(BM_Geometric)->DenseRange(2, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_Workspace)->DenseRange(2, 6)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_QpOnly)->DenseRange(2, 6)->Unit(benchmark::kMicrosecond);
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
      const int n = std::stoi(run.run_name.args);
      Row& row = rows_[run.run_name.function_name][n];
      row.us = run.GetAdjustedRealTime();
      auto counter = [&](const char* key) {
        auto it = run.counters.find(key);
        return it == run.counters.end() ? -1.0 : double(it->second);
      };
      row.allocs = counter("allocs");
      row.instructions = counter("instr");
      row.qp_iterations = counter("qp_iter");
    }
  }
  void Finalize() override {
    ConsoleReporter::Finalize();
    std::printf(
        "\n| contacts | one-off Solve (us) | workspace Solve (us) | QP alone (us) | QP / workspace "
        "|"
        " QP iterations | ipopt (us) | ipopt / workspace | allocs per solve (one-off / workspace) |"
        " instructions per workspace solve / QP alone |\n"
        "|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const auto& [n, w] : rows_["BM_Workspace"]) {
      const Row g = rows_["BM_Geometric"][n], q = rows_["BM_QpOnly"][n], i = rows_["BM_Ipopt"][n];
      char instructions[64] = "n/a (scripts/count_instructions.sh)";
      if (w.instructions >= 0) {
        std::snprintf(instructions, sizeof(instructions), "%.0f / %.0f", w.instructions,
                      q.instructions);
      }
      std::printf("| %d | %.2f | %.2f | %.2f | %.2f | %.1f | %.1f | %.0fx | %.1f / %.1f | %s |\n",
                  n, g.us, w.us, q.us, q.us / w.us, w.qp_iterations, i.us, i.us / w.us, g.allocs,
                  w.allocs, instructions);
    }
  }

 private:
  struct Row {
    double us = 0, allocs = -1, instructions = -1, qp_iterations = -1;
  };
  std::map<std::string, std::map<int, Row>> rows_;
};

}  // namespace
}  // namespace tactforce::planner

namespace tactforce::planner {
namespace {

// --callgrind-run=N,C[,qp]: no Google Benchmark; N workspace solves of the
// C-contact grasps (cycling over all 64, after one warm-up pass), or with
// ",qp" N solves of their FE-plane QPs alone (TimedQpSolve), for
// scripts/count_instructions.sh to count under callgrind; ",dispatch": N
// Plan requests through api::PlanDispatcher inline (TimedDispatchPlan),
// ",cross": N CROSS_CHECK solves in place (TimedCrossCheckSolve).
int CallgrindQpRun(int solves, int contacts) {
  const auto& qps = PlaneQps(contacts);
  DenseQpWorkspace workspace;
  DenseQpResult result;
  for (const DenseQp& qp : qps) SolveDenseQp(qp, {}, &workspace, &result);
  int failures = 0;
  int64_t iterations = 0, active = 0;
  for (int i = 0; i < solves; ++i) {
    if (!TimedQpSolve(qps[i % qps.size()], &workspace, &result)) ++failures;
    iterations += result.iterations;
    active += static_cast<int64_t>(result.active_set.size());
  }
  std::printf(
      "%d QP solves of %d contacts, %.2f iterations each, %.2f rows active at the end, %d "
      "failures\n",
      solves, contacts, static_cast<double>(iterations) / solves,
      static_cast<double>(active) / solves, failures);
  return failures == 0 ? 0 : 1;
}

// A caller that never stops (the inline dispatch of a Plan).
class NeverStop final : public api::CallControl {
 public:
  bool ShouldStop() const override { return false; }
  absl::Status StopReason(std::string_view) const override { return absl::OkStatus(); }
  std::string Peer() const override { return ""; }
};

// The timed call of the dispatch run: one Planner.Plan request through
// api::PlanDispatcher (inline: GEOMETRIC, <= 8 contacts), conversion,
// limits, solve and response included.
bool DispatchPlan(const api::PlanDispatcher& dispatcher, const v1::PlanRequest& request,
                  v1::PlanResponse* response) {
  static const NeverStop control;
  bool ok = false;
  dispatcher.Dispatch(request, response, api::CallLog("Plan", control), control,
                      [&ok](const absl::Status& s) { ok = s.ok(); });
  return ok && response->status() == v1::PLAN_STATUS_OPTIMAL;
}
[[gnu::noinline]] bool TimedDispatchPlan(const api::PlanDispatcher& dispatcher,
                                         const v1::PlanRequest& request,
                                         v1::PlanResponse* response) {
  return DispatchPlan(dispatcher, request, response);
}

// The timed call of the cross-check run: GEOMETRIC and IPOPT compared.
bool CrossCheckSolve(const PlanProblem& problem, PlanningWorkspace* workspace, PlanResult* result) {
  return Plan(problem, PlanOptions{}, SolverKind::kCrossCheck, workspace, result).ok() &&
         result->status == PlanStatus::kOptimal;
}
[[gnu::noinline]] bool TimedCrossCheckSolve(const PlanProblem& problem,
                                            PlanningWorkspace* workspace, PlanResult* result) {
  return CrossCheckSolve(problem, workspace, result);
}

// --callgrind-run=N,C,dispatch and --callgrind-run=N,C,cross (see below).
int CallgrindDispatchRun(int solves, int contacts, bool cross) {
  spdlog::set_level(spdlog::level::warn);  // the call log line is not what is measured
  const auto& grasps = Grasps(contacts);
  std::vector<v1::PlanRequest> requests;
  for (const PlanProblem& p : grasps) {
    requests.push_back(api::ToRequest(p, PlanOptions{}, SolverKind::kGeometric));
  }
  const api::PlanDispatcher dispatcher(nullptr, api::PlanSettings{});
  PlanningWorkspace workspace;
  PlanResult result;
  v1::PlanResponse response;
  for (size_t g = 0; g < grasps.size(); ++g) {  // warm-up, not counted
    (void)(cross ? CrossCheckSolve(grasps[g], &workspace, &result)
                 : DispatchPlan(dispatcher, requests[g], &response));
  }
  int failures = 0;
  for (int i = 0; i < solves; ++i) {
    const size_t g = i % grasps.size();
    const bool ok = cross ? TimedCrossCheckSolve(grasps[g], &workspace, &result)
                          : TimedDispatchPlan(dispatcher, requests[g], &response);
    if (!ok) ++failures;
  }
  std::printf("%d %s runs of %d contacts (after one warm-up pass), %d failures\n", solves,
              cross ? "cross-check" : "dispatch", contacts, failures);
  return failures == 0 ? 0 : 1;
}

int CallgrindRun(const std::string& spec) {
  const size_t comma = spec.find(',');
  const int solves = std::stoi(spec.substr(0, comma));
  const std::string rest = comma == std::string::npos ? "" : spec.substr(comma + 1);
  const int contacts = rest.empty() ? 4 : std::stoi(rest);
  if (rest.find(",qp") != std::string::npos) return CallgrindQpRun(solves, contacts);
  if (rest.find(",dispatch") != std::string::npos)
    return CallgrindDispatchRun(solves, contacts, false);
  if (rest.find(",cross") != std::string::npos) return CallgrindDispatchRun(solves, contacts, true);
  const auto& grasps = Grasps(contacts);
  const auto solver = MakeSolver(SolverKind::kGeometric);
  PlanningWorkspace workspace;
  PlanResult result;
  for (const PlanProblem& p : grasps) (void)solver->Solve(p, PlanOptions{}, &workspace, &result);
  int failures = 0;
  for (int i = 0; i < solves; ++i) {
    if (!TimedWorkspaceSolve(*solver, grasps[i % grasps.size()], PlanOptions{}, &workspace,
                             &result)) {
      ++failures;
    }
  }
  std::printf("%d solves of %d contacts, %d failures\n", solves, contacts, failures);
  return failures == 0 ? 0 : 1;
}

}  // namespace
}  // namespace tactforce::planner

int main(int argc, char** argv) {
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg.rfind("--callgrind-run=", 0) == 0) {
      return tactforce::planner::CallgrindRun(arg.substr(16));
    }
  }
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  tactforce::planner::RatioReporter reporter;
  benchmark::RunSpecifiedBenchmarks(&reporter);
  benchmark::Shutdown();
  return 0;
}
