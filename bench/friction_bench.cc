// Friction-from-slip accuracy on simulated probing trials: median |mu error|
// over 10 trials per surface, for the paper's 5-sample window average and
// our linear fit, across force noise and normal-force ramp rate.
//
//   build/bin/friction_bench
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include "tactforce/estimator/friction.h"

using namespace tactforce::estimator;

namespace {

// Median |mu error| over the surfaces mu = 0.2, 0.3, ..., 1.0 (pooled trials)
// and the worst surface's median.
std::pair<double, double> Score(double noise, double ramp, PreSlipForce mode) {
  std::vector<double> pooled;
  double worst = 0.0;
  for (int k = 0; k <= 8; ++k) {
    FrictionSimOptions sim;
    sim.mu = 0.2 + 0.1 * k;
    sim.trials = 10;
    sim.force_noise = noise;
    sim.ramp = ramp;
    sim.seed = 1000 + k;
    const SimulatedFriction data = SimulateFriction(sim);
    FrictionOptions o;
    o.pre_slip = mode;
    auto e = EstimateFriction(data.trials, o);
    std::vector<double> err;
    if (e.ok()) {
      for (const auto& t : e->trials)
        err.push_back(t.valid && t.slipped ? std::abs(t.mu - sim.mu) : 1.0);
    }
    std::sort(err.begin(), err.end());
    const double med = err.empty() ? 1.0 : 0.5 * (err[4] + err[5]);
    worst = std::max(worst, med);
    pooled.insert(pooled.end(), err.begin(), err.end());
  }
  std::sort(pooled.begin(), pooled.end());
  return {pooled[pooled.size() / 2], worst};
}

}  // namespace

int main() {
  std::printf(
      "Median |mu error| (pooled over mu = 0.2..1.0, 10 trials each; worst surface's median in "
      "brackets)\n\n");
  std::printf(
      "| force noise (N) | ramp (N/s) | window average (paper) | linear fit (ours) "
      "|\n|---:|---:|---:|---:|\n");
  for (double noise : {0.01, 0.05, 0.1}) {
    for (double ramp : {0.25, 0.5, 1.0, 2.0}) {
      const auto a = Score(noise, ramp, PreSlipForce::kWindowAverage);
      const auto b = Score(noise, ramp, PreSlipForce::kLinearFit);
      std::printf("| %.2f | %.2f | %.4f [%.4f] | %.4f [%.4f] |\n", noise, ramp, a.first, a.second,
                  b.first, b.second);
    }
  }
  return 0;
}
