// Hidden-effect tests for the second forms of two effects (issue 6):
// Prandtl-Ishlinskii hysteresis (must be named 'hysteresis') and a power-law
// nonlinearity (must be named 'nonlinearity', exponent within
// +/-(0.01 + 2 %)). >= 200 seeds each, >= 95 % correct. Seeds on 2 threads.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <iostream>
#include <map>
#include <mutex>
#include <thread>

#include "gtest/gtest.h"
#include "hidden_effects.h"

namespace tactforce::audit {
namespace {

using testing::CheckParameters;
using testing::FastOptions;
using testing::ForSeeds;
using testing::HiddenCase;
using testing::HiddenForm;
using testing::MakeHiddenCase;

constexpr int kSeeds = 200;

struct Tally {
  std::atomic<int> named{0}, recovered{0}, correct{0}, extra{0};
  std::map<std::string, int> forms;
  std::vector<std::string> failures, extras;
  std::vector<double> errors;      // |got - want| of the checked parameter
  std::vector<double> rel_errors;  // |got - want| / want
  std::mutex mu;
};

void RunForm(Effect e, HiddenForm form, uint64_t seed_base, Tally* t) {
  ForSeeds(kSeeds, [&](int i) {
    const uint64_t seed = seed_base + i;
    HiddenCase hc = MakeHiddenCase({e}, seed, form);
    auto rep = RunAudit(hc.data, FastOptions(hc));
    std::string why;
    bool named = false, recovered = false;
    if (!rep.ok()) {
      why = std::string(rep.status().message());
    } else if (rep->causes.empty() || rep->causes[0].effect != EffectName(e)) {
      why = "named " + (rep->causes.empty() ? std::string("nothing") : rep->causes[0].effect);
    } else {
      named = true;
      const Cause& c = rep->causes[0];
      auto r = CheckParameters(e, hc.model.effects, c);
      recovered = r.ok;
      std::lock_guard<std::mutex> lock(t->mu);
      t->forms[c.form]++;
      {
        // Parameter error of the checked quantity.
        const auto& tr = hc.model.effects;
        auto get = [&](const char* k) {
          auto it = c.parameters.find(k);
          return it == c.parameters.end() ? NAN : it->second;
        };
        double got = NAN, want = NAN;
        if (e == Effect::kNonlinearity) {
          got = get("power_exponent");
          want = tr.power_exponent;
        } else {
          got = c.form == "play" ? get("hysteresis_width") : get("loop_width");
          want = testing::PiLoopWidth(tr);
        }
        t->errors.push_back(std::abs(got - want));
        t->rel_errors.push_back(std::abs(got - want) / std::abs(want));
      }
      if (rep->causes.size() > 1) {
        t->extra++;
        t->extras.push_back("seed " + std::to_string(seed) + ": also named " +
                            rep->causes[1].effect);
      }
      if (!r.ok)
        t->failures.push_back("seed " + std::to_string(seed) + " (parameter, form " + c.form +
                              "): " + r.what);
      if (!(c.gain > 0 && rep->gain > 0)) why = "gain not positive";
    }
    if (named) t->named++;
    if (recovered) t->recovered++;
    if (named && why.empty()) t->correct++;
    if (!why.empty()) {
      std::lock_guard<std::mutex> lock(t->mu);
      t->failures.push_back("seed " + std::to_string(seed) + ": " + why);
    }
  });
}

void Print(const char* label, const Tally& t) {
  std::cout << "[hidden " << label << "] named first with positive gain " << t.correct << "/"
            << kSeeds << " = " << 100.0 * t.correct / kSeeds << " %; parameter within tolerance "
            << t.recovered << "/" << kSeeds << "; with an extra cause " << t.extra
            << "; forms named:";
  for (const auto& [f, n] : t.forms) std::cout << " " << (f.empty() ? "-" : f) << "=" << n;
  std::cout << "\n";
  auto stats = [](std::vector<double> v, const char* what) {
    if (v.empty()) return;
    std::sort(v.begin(), v.end());
    std::cout << "  " << what << ": median " << v[v.size() / 2] << ", 95th percentile "
              << v[v.size() * 95 / 100] << ", max " << v.back() << "\n";
  };
  stats(t.errors, "abs error");
  stats(t.rel_errors, "rel error");
  for (const auto& f : t.failures) std::cout << "  " << f << "\n";
  for (const auto& f : t.extras) std::cout << "  (extra) " << f << "\n";
}

TEST(HiddenForms, PrandtlIshlinskiiHysteresisNamedHysteresis) {
  Tally t;
  RunForm(Effect::kHysteresis, HiddenForm::kPrandtlIshlinskii, 1100000, &t);
  Print("hysteresis/prandtl_ishlinskii", t);
  EXPECT_GE(t.correct, 0.95 * kSeeds);
  // The loop width (2 sum w r) is reported; its recovery is not required for
  // the naming criterion but must hold in most seeds.
  EXPECT_GE(t.recovered, 0.90 * kSeeds);
}

TEST(HiddenForms, PowerLawNamedNonlinearityExponentRecovered) {
  Tally t;
  RunForm(Effect::kNonlinearity, HiddenForm::kPowerLaw, 1200000, &t);
  Print("nonlinearity/power_law", t);
  EXPECT_GE(t.correct, 0.95 * kSeeds);
  EXPECT_GE(t.recovered, 0.95 * kSeeds);
}

// The new forms next to a second effect: PI hysteresis + each other effect
// type, power law + each other effect type (14 pairs, 8 seeds each): both
// named in >= 90 % (the two-effect criterion).
TEST(HiddenForms, NewFormsWithASecondEffectBothNamed) {
  std::vector<std::pair<Effect, HiddenForm>> pairs_first = {
      {Effect::kHysteresis, HiddenForm::kPrandtlIshlinskii},
      {Effect::kNonlinearity, HiddenForm::kPowerLaw}};
  struct Pair {
    Effect a, b;
    HiddenForm form;
  };
  std::vector<Pair> pairs;
  for (const auto& [e, f] : pairs_first)
    for (Effect o : AllEffects())
      if (o != e) pairs.push_back({e, o, f});
  const int n = 8 * static_cast<int>(pairs.size());
  std::atomic<int> both{0};
  std::mutex mu;
  std::vector<std::string> failures;
  ForSeeds(n, [&](int i) {
    const Pair& p = pairs[i % pairs.size()];
    const uint64_t seed = 1300000 + i;
    HiddenCase hc = MakeHiddenCase({p.a, p.b}, seed, p.form);
    auto rep = RunAudit(hc.data, FastOptions(hc));
    bool fa = false, fb = false;
    std::string got;
    if (rep.ok())
      for (const auto& c : rep->causes) {
        fa = fa || c.effect == EffectName(p.a);
        fb = fb || c.effect == EffectName(p.b);
        got += c.effect + (c.form.empty() ? "" : "/" + c.form) + " ";
      }
    if (fa && fb) {
      ++both;
    } else {
      std::lock_guard<std::mutex> lock(mu);
      failures.push_back("seed " + std::to_string(seed) + " " + EffectName(p.a) +
                         (p.form == HiddenForm::kPowerLaw ? "/power_law" : "/prandtl_ishlinskii") +
                         "+" + EffectName(p.b) + ": named " + (got.empty() ? "nothing" : got));
    }
  });
  std::cout << "[two effects, new forms] both named " << both << "/" << n << " = "
            << 100.0 * both / n << " %\n";
  for (const auto& f : failures) std::cout << "  " << f << "\n";
  EXPECT_GE(both, 0.90 * n);
}

}  // namespace
}  // namespace tactforce::audit
