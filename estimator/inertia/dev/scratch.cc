#include <cstdio>
#include <cmath>
#include <vector>
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/simulate.h"
using namespace tactforce::inertia;
int main(int argc, char** argv) {
  double ps = argc > 1 ? atof(argv[1]) : 1e-4, rs = argc > 2 ? atof(argv[2]) : 1e-3;
  const char* names[] = {"LS", "LS+SG", "FG", "constrained", "constr (noise unknown)"};
  double riem[5] = {0}, paper[5] = {0}, mass[5] = {0}; int n = 4; int cons[5] = {0};
  for (int seed = 1; seed <= n; ++seed) {
    SimulationOptions so; so.noise.force_sigma = 0.5; so.noise.position_sigma = ps; so.noise.orientation_sigma = rs; so.seed = seed;
    auto sim = SimulateInertia(so);
    for (int v = 0; v < 5; ++v) {
      InertiaOptions o; o.noise.force_sigma = 0.5; o.noise.position_sigma = ps; o.noise.orientation_sigma = rs;
      if (v <= 1) o.method = InertiaMethod::kBaselineLs;
      if (v == 1) o.savitzky_golay = true;
      if (v == 2) o.method = InertiaMethod::kFactorGraph;
      if (v == 4) o.noise = {};
      auto f = FitInertia(sim->samples, o);
      auto e = CompareInertia(sim->truth.params, f->params);
      riem[v] += e.riemannian / n; paper[v] += e.paper_metric / n; mass[v] += e.mass_percent / n; cons[v] += e.consistent;
      if (seed == 1 && v >= 3) for (auto& s : f->notes) printf("   %s\n", s.c_str());
    }
  }
  for (int v = 0; v < 5; ++v) printf("%-24s riem %.4f paper %.4f mass%% %.3f cons %d/%d\n", names[v], riem[v], paper[v], mass[v], cons[v], n);
}
