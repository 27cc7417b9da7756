// Force-estimation accuracy and speed: PROJECTION (GeoDEx) vs NORMAL_LSQ
// (ours) on seeded random grasps whose tactile readings carry the GeoDEx
// error ranges (activation threshold 0.1-0.5 N, hysteresis residual up to
// 0.2 N, force error 0.1-0.5 N, noise 0.01-0.03 N), drawn per contact.
//
//   build/bin/estimation_bench
//
// Counters: rms_force_error (N, over all force components of all contacts,
// against the true equilibrium forces) and the time per estimate.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "tactforce/estimator/force_estimation.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"

namespace tactforce {
namespace {

struct Case {
  planner::PlanProblem problem;
  std::vector<planner::Vec3> truth;
  std::vector<double> readings;
};

// True forces: the robust plan moved randomly along the FE-plane while every
// contact stays inside its friction cone with some normal force.
std::vector<Case> MakeCases(int count, bool with_extrinsic) {
  std::mt19937_64 rng(with_extrinsic ? 77 : 76);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  planner::RandomGraspOptions ro;
  ro.min_contacts = 3;
  ro.max_mass = 0.5;  // hand-held objects, as in the GeoDEx experiments
  ro.infeasible_fraction = 0.0;
  ro.extrinsic_probability = with_extrinsic ? 0.3 : 0.0;
  std::vector<Case> out;
  while (static_cast<int>(out.size()) < count) {
    planner::RandomGrasp g = planner::MakeRandomGrasp(rng, ro);
    for (auto& c : g.problem.contacts)
      c.sigma = c.kind == planner::ContactKind::kIntrinsic ? 0.3 : 0.0;
    int intrinsic = 0;
    for (auto& c : g.problem.contacts) intrinsic += c.kind == planner::ContactKind::kIntrinsic;
    if (intrinsic == 0) continue;
    auto plan = planner::Plan(g.problem, planner::PlanOptions{}, planner::SolverKind::kGeometric);
    if (!plan.ok() || plan->status != planner::PlanStatus::kOptimal) continue;
    const auto eq = planner::ComputeForceEquilibrium(g.problem, 1e-9);
    Eigen::VectorXd f(3 * g.problem.contacts.size());
    for (size_t i = 0; i < plan->forces.size(); ++i) f.segment<3>(3 * i) = plan->forces[i];
    for (int attempt = 0; attempt < 20; ++attempt) {
      // An isotropic step on the FE-plane, drawn in force space and
      // projected (B B^T step), so the data do not depend on which orthonormal
      // basis B the planner happens to compute.
      Eigen::VectorXd step(f.size());
      for (int k = 0; k < step.size(); ++k) step(k) = 0.5 * gauss(rng);
      const Eigen::VectorXd candidate = f + eq.null_basis * (eq.null_basis.transpose() * step);
      bool inside = true;
      for (size_t i = 0; i < g.problem.contacts.size() && inside; ++i) {
        const auto& c = g.problem.contacts[i];
        const Eigen::Vector3d fi = candidate.segment<3>(3 * i);
        const double fn = c.normal.normalized().dot(fi);
        inside = fn > 0.2 && (fi - fn * c.normal.normalized()).norm() < c.friction * fn;
      }
      if (inside) {
        f = candidate;
        break;
      }
    }
    Case k;
    k.problem = g.problem;
    for (size_t i = 0; i < g.problem.contacts.size(); ++i) {
      k.truth.push_back(f.segment<3>(3 * i));
      const auto& c = g.problem.contacts[i];
      if (c.kind != planner::ContactKind::kIntrinsic) continue;
      const double fn = c.normal.normalized().dot(k.truth.back());
      const double threshold = 0.1 + 0.4 * u(rng);
      const double hysteresis = 0.2 * u(rng);
      const double error = (u(rng) < 0.5 ? -1 : 1) * (0.1 + 0.4 * u(rng));
      const double noise = (0.01 + 0.02 * u(rng)) * gauss(rng);
      double reading = fn < threshold ? 0.0 : fn + error + hysteresis * u(rng) + noise;
      k.readings.push_back(std::max(0.0, reading));
    }
    out.push_back(std::move(k));
  }
  return out;
}

void BM_Estimate(benchmark::State& state, estimator::EstimateMethod method, bool extrinsic) {
  static const std::vector<Case> grasp_cases = MakeCases(300, false);
  static const std::vector<Case> extrinsic_cases = MakeCases(300, true);
  const std::vector<Case>& cases = extrinsic ? extrinsic_cases : grasp_cases;
  estimator::EstimateOptions o;
  o.method = method;
  // Accuracy over every case, once.
  double sq = 0.0;
  long n = 0, failures = 0;
  std::vector<double> per_case;
  for (const Case& c : cases) {
    auto e = estimator::EstimateForces(c.problem, c.readings, o);
    if (!e.ok() || e->status != estimator::EstimateStatus::kOk) {
      ++failures;
      continue;
    }
    double case_sq = 0.0;
    for (size_t i = 0; i < c.truth.size(); ++i) {
      case_sq += (e->forces[i] - c.truth[i]).squaredNorm();
    }
    sq += case_sq;
    n += 3 * static_cast<long>(c.truth.size());
    per_case.push_back(std::sqrt(case_sq / (3.0 * c.truth.size())));
  }
  std::sort(per_case.begin(), per_case.end());
  size_t i = 0;
  for (auto _ : state) {
    auto e = estimator::EstimateForces(cases[i % cases.size()].problem,
                                       cases[i % cases.size()].readings, o);
    benchmark::DoNotOptimize(e);
    ++i;
  }
  state.counters["rms_force_error_N"] = std::sqrt(sq / std::max(1L, n));
  state.counters["median_case_rms_N"] = per_case.empty() ? 0.0 : per_case[per_case.size() / 2];
  state.counters["failures"] = static_cast<double>(failures);
  state.counters["cases"] = static_cast<double>(cases.size());
}

BENCHMARK_CAPTURE(BM_Estimate, projection_grasp, estimator::EstimateMethod::kProjection, false)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Estimate, normal_lsq_grasp, estimator::EstimateMethod::kNormalLsq, false)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Estimate, projection_extrinsic, estimator::EstimateMethod::kProjection, true)
    ->Unit(benchmark::kMicrosecond);
BENCHMARK_CAPTURE(BM_Estimate, normal_lsq_extrinsic, estimator::EstimateMethod::kNormalLsq, true)
    ->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace tactforce

BENCHMARK_MAIN();
