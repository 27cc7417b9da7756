#include <cstdio>
#include <cmath>
#include <ctime>
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/simulate.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/inertia/truth.h"
using namespace tactforce::inertia;
double Cpu() { timespec ts; clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts); return ts.tv_sec + 1e-9*ts.tv_nsec; }
int main(int argc, char** argv) {
  double dur = argc > 1 ? atof(argv[1]) : 10;
  for (double var : kPaperForceVariances) {
    SimulationOptions so; so.noise.force_sigma = std::sqrt(var); so.seed = 3; so.duration = dur;
    auto sim = SimulateInertia(so);
    if (!sim.ok()) { printf("%s\n", std::string(sim.status().message()).c_str()); return 1; }
    for (auto m : {InertiaMethod::kBaselineLs, InertiaMethod::kFactorGraph, InertiaMethod::kConstrained}) {
      InertiaOptions o; o.method = m; o.noise.force_sigma = std::sqrt(var);
      double c0 = Cpu();
      auto f = FitInertia(sim->samples, o);
      double cpu = Cpu() - c0;
      if (!f.ok()) { printf("%s\n", std::string(f.status().message()).c_str()); continue; }
      auto e = CompareInertia(sim->truth.params, f->params);
      printf("var %.2f %-12s paper %.4g riem %.4g mass%% %.3g com %.3g mm cons %d it %d cpu %.1f ms\n", var, ToString(m),
             e.paper_metric, e.riemannian, e.mass_percent, e.com_mm, e.consistent, f->iterations, cpu*1e3);
      if (m == InertiaMethod::kFactorGraph) { auto a = f->params.inertia_com.ToArray(); printf("   m %.4f c %.4f %.4f %.4f I %.2f %.2f %.2f %.2f %.2f %.2f\n", f->params.mass, f->params.com.x(), f->params.com.y(), f->params.com.z(), a[0]*100,a[1]*100,a[2]*100,a[3]*100,a[4]*100,a[5]*100);
        for (auto& n : f->notes) printf("   note: %s\n", n.c_str()); }
    }
  }
}
