#include <cstdio>
#include <cmath>
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/truth.h"
using namespace tactforce::inertia;
int main(int argc, char** argv) {
  for (double var : kPaperForceVariances) {
    SimulationOptions so; so.noise.force_sigma = std::sqrt(var); so.seed = 3;
    auto sim = SimulateInertia(so);
    if (!sim.ok()) { printf("%s\n", std::string(sim.status().message()).c_str()); return 1; }
    for (auto m : {InertiaMethod::kBaselineLs, InertiaMethod::kConstrained}) {
      InertiaOptions o; o.method = m; o.noise.force_sigma = std::sqrt(var);
      auto f = FitInertia(sim->samples, o);
      if (!f.ok()) { printf("%s\n", std::string(f.status().message()).c_str()); continue; }
      auto e = CompareInertia(sim->truth.params, f->params);
      printf("var %.2f %-12s paper %.4g riem %.4g mass%% %.3g com %.3g mm cons %d it %d t %.3f ms\n", var, ToString(m),
             e.paper_metric, e.riemannian, e.mass_percent, e.com_mm, e.consistent, f->iterations, f->time_seconds*1e3);
      for (auto& n : f->notes) printf("   note: %s\n", n.c_str());
    }
  }
}
