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
  std::string dir = "/work/shared/data/inertia/";
  int seeds = argc > 2 ? atoi(argv[2]) : 5;
  std::string level = argc > 1 ? argv[1] : "moderate";
  for (const char* tool : {"Hammer", "Screwdriver", "Pliers", "Ruler", "C_Clamp"}) {
    auto s0 = ReadInertiaCsvFile(dir + tool + ".csv");
    auto truth = ReadTruthJsonFile(dir + tool + ".truth.json");
    auto noise = *NadeauNoise(level);
    double size = EquivalentBoxSize(truth->params);
    for (auto m : {InertiaMethod::kBaselineLs, InertiaMethod::kConstrained, InertiaMethod::kFactorGraph}) {
      double sm=0, sc=0, sr=0, sp=0, cons=0, cpu=0; int cnt=0;
      for (int seed = 1; seed <= seeds; ++seed) {
        InertiaSamples s = *s0; AddNoise(s, noise, seed);
        InertiaOptions o; o.method = m; 
        o.noise.force_sigma = noise.force_sigma; o.noise.torque_sigma = noise.torque_sigma;
        o.noise.linear_acceleration_sigma = noise.linear_acceleration_sigma; o.noise.angular_acceleration_sigma = noise.angular_acceleration_sigma;
        double c0 = Cpu(); auto f = FitInertia(s, o); cpu += Cpu()-c0;
        if (!f.ok()) { printf("%s\n", std::string(f.status().message()).c_str()); continue; }
        auto e = CompareInertia(truth->params, f->params);
        sm += e.mass_percent; sc += e.com_mm/1000/size*100; sr += std::isfinite(e.riemannian)? e.riemannian : 0; sp += e.paper_metric; cons += e.consistent; ++cnt;
        if (seed==1 && m==InertiaMethod::kConstrained) for (auto& n : f->notes) printf("   note: %s\n", n.c_str());
      }
      printf("%-12s %-12s mass%% %.3f com%% %.3f riem(finite) %.3f paper %.3f cons %.0f%% cpu %.1f ms (size %.3f m)\n", tool, ToString(m), sm/cnt, sc/cnt, sr/cnt, sp/cnt, 100*cons/cnt, 1e3*cpu/cnt, size);
    }
  }
}
