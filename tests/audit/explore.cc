#include <chrono>
#include <cstdio>
#include <cstdlib>

#include "hidden_effects.h"

using namespace tactforce::audit;
using namespace tactforce::audit::testing;

int main(int argc, char** argv) {
  int seeds = argc > 1 ? atoi(argv[1]) : 20;
  int only = argc > 2 ? atoi(argv[2]) : -1;
  AuditOptions opt;
  opt.downstream_gain = false;
  opt.uncertainties = false;
  for (int ei = -1; ei < kNumEffects; ++ei) {
    if (only >= -1 && only != -2 && ei != only && argc > 2) continue;
    std::vector<Effect> eff;
    if (ei >= 0) eff.push_back(AllEffects()[ei]);
    int named = 0, params = 0, extra = 0;
    auto t0 = std::chrono::steady_clock::now();
    long nsamp = 0;
    for (int s = 1; s <= seeds; ++s) {
      auto hc = MakeHiddenCase(eff, 1000 * (ei + 2) + s);
      nsamp += hc.data.t.size();
      opt.reading_units = hc.model.units;
      auto rep = RunAudit(hc.data, opt);
      if (!rep.ok()) { printf("error %s\n", std::string(rep.status().message()).c_str()); continue; }
      if (eff.empty()) {
        if (rep->nominal_adequate) ++named;
        else printf("  null seed %d: named %s gain %.2f\n", s, rep->causes[0].effect.c_str(), rep->causes[0].gain);
        continue;
      }
      bool ok_name = !rep->causes.empty() && rep->causes[0].effect == EffectName(eff[0]);
      if (ok_name) {
        ++named;
        auto r = CheckParameters(eff[0], hc.model.effects, rep->causes[0]);
        if (r.ok && rep->causes[0].gain > 0) ++params;
        else printf("  %s seed %d rate %.0f: params %s\n", EffectName(eff[0]), s, hc.sim.rate, r.what.c_str());
        if (rep->causes.size() > 1) { ++extra; printf("  %s seed %d extra %s gain %.2f\n", EffectName(eff[0]), s, rep->causes[1].effect.c_str(), rep->causes[1].gain);}
      } else {
        printf("  %s seed %d rate %.0f noise %.3f: named %s (gain %.2f)\n", EffectName(eff[0]), s, hc.sim.rate, hc.model.noise,
               rep->causes.empty() ? "none" : rep->causes[0].effect.c_str(), rep->causes.empty() ? 0 : rep->causes[0].gain);
      }
    }
    double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
    printf("%-12s named %d/%d params %d extra %d  %.1f ms/audit  %.0f samples\n", ei < 0 ? "null" : EffectName(eff[0]), named, seeds, params, extra,
           ms / seeds, double(nsamp) / seeds);
    fflush(stdout);
  }
}
