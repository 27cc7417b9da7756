// The issue-26 evaluations of the audit over many seeds (not a ctest: a few
// minutes on 2 cores; the CI-sized checks are in taxel_test.cc):
//   partial  hidden partial_activation (1-8 dead taxels of 42): named first
//            with the fraction within one taxel; and without dead taxels: not
//            named
//   phantom  a phantom force (0.2-1 N, decay 0.3-3 s): named, named first,
//            phantom_force within +/-(0.05 N + 20 %)
//   late     each of the eight effects only in the last third of the run:
//            named (any rank), named first, parameter within the
//            hidden-effect tolerance, the last block among those showing it
// Usage: audit_hidden_eval [--seeds N] [--first-seed I] [--blocks K]
//          [--suite partial|phantom|late|all] [--effect E (late: only E)]
//        audit_hidden_eval --suite one|one-late --seed S [--effect E [--effect2 E2]]
// Seed indices I .. I + N - 1 (0-199 and 1000-1199 are the README's two
// ranges). Prints one line per case type and every failure; a late
// saturation's failure also says how much of the last third lies above the
// saturation level (none: the data hold no trace of it). one: the summary of
// one hidden-effect case (one-late: its late-only variant).
#include <algorithm>
#include <atomic>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <string>

#include "hidden_effects.h"

namespace tactforce::audit {
namespace {

using testing::FastOptions;
using testing::ForSeeds;

struct Args {
  int seeds = 200;
  int blocks = 4;
  std::string suite = "all";
  int first_seed = 0;   // seed indices first_seed .. first_seed + seeds - 1
  long long seed = -1;  // --suite one: the hidden-effect case of this seed, summary printed
  bool late = false;    // --suite one-late: MakeLateCase
  std::string effect2;  // --suite one: a second hidden effect (--effect2)
  std::string effect;   // --suite one: the hidden effect (empty: the null case)
};

// One hidden-effect case (MakeHiddenCase({effect}, seed)): prints the summary.
void One(const Args& a) {
  std::vector<Effect> effects;
  if (!a.effect.empty()) effects.push_back(*ParseEffect(a.effect));
  if (!a.effect2.empty()) effects.push_back(*ParseEffect(a.effect2));
  auto hc = a.late && effects.size() == 1
                ? testing::MakeLateCase(effects[0], static_cast<uint64_t>(a.seed))
                : testing::MakeHiddenCase(effects, static_cast<uint64_t>(a.seed));
  AuditOptions o = FastOptions(hc);
  o.blocks = a.blocks;
  auto rep = RunAudit(hc.data, o);
  if (!rep.ok()) {
    std::cout << rep.status() << "\n";
    return;
  }
  std::cout << FormatAuditSummary(*rep);
  for (const auto& c : rep->candidates)
    if (c.accepted)
      std::cout << "accepted round " << c.round << " " << c.effect << " rms " << c.heldout_rms
                << "\n";
}

void Report(const std::string& what, int good, int n, const std::vector<std::string>& failures) {
  std::cout << what << " " << good << "/" << n << " = " << 100.0 * good / n << " %\n";
  for (const auto& f : failures) std::cout << "    " << f << "\n";
}

void PartialActivation(const Args& a) {
  std::atomic<int> named_first{0}, fraction_ok{0}, clean_not_named{0};
  std::mutex mu;
  std::vector<std::string> fails, false_named;
  ForSeeds(a.seeds, [&](int j) {
    const int i = a.first_seed + j;
    const int dead = 1 + i % 8;
    auto tc = testing::MakeTaxelCase(2600000 + i, dead);
    AuditOptions o;
    o.downstream_gain = false;
    o.uncertainties = false;
    o.blocks = a.blocks;
    auto rep = RunAudit(tc.data, o);
    std::string why;
    if (!rep.ok()) {
      why = std::string(rep.status().message());
    } else if (rep->causes.empty() || rep->causes[0].effect != kPartialActivation) {
      why = "named first " + (rep->causes.empty() ? std::string("nothing") : rep->causes[0].effect);
    } else {
      ++named_first;
      const double got = rep->causes[0].parameters.at("silent_taxels");
      if (std::abs(got - dead) <= 1)
        ++fraction_ok;
      else
        why = "silent " + std::to_string(got) + " want " + std::to_string(dead);
    }
    if (!why.empty()) {
      std::lock_guard<std::mutex> lock(mu);
      fails.push_back("seed " + std::to_string(2600000 + i) + ": " + why);
    }
    auto clean = testing::MakeTaxelCase(2700000 + i, 0);
    auto rc = RunAudit(clean.data, o);
    bool named = !rc.ok();
    if (rc.ok())
      for (const auto& c : rc->causes) named = named || c.effect == kPartialActivation;
    if (!named) {
      ++clean_not_named;
    } else {
      std::lock_guard<std::mutex> lock(mu);
      false_named.push_back("seed " + std::to_string(2700000 + i) + ": " +
                            (rc.ok() ? "named with fraction " +
                                           std::to_string(rc->causes[0].parameters.at("fraction"))
                                     : std::string(rc.status().message())));
    }
  });
  Report("[partial_activation] named first", named_first, a.seeds, {});
  Report("[partial_activation] named first + silent taxels within one", fraction_ok, a.seeds,
         fails);
  Report("[partial_activation] without dead taxels: not named", clean_not_named, a.seeds,
         false_named);
}

void Phantom(const Args& a) {
  std::atomic<int> named{0}, first{0}, correct{0};
  std::mutex mu;
  std::vector<std::string> fails;
  ForSeeds(a.seeds, [&](int i) {
    const uint64_t seed = 2800000 + a.first_seed + i;
    auto pc = testing::MakePhantomCase(seed);
    AuditOptions o = FastOptions(pc.hc);
    o.blocks = a.blocks;
    auto rep = RunAudit(pc.hc.data, o);
    std::string why = "not named";
    std::string got;
    if (rep.ok())
      for (size_t k = 0; k < rep->causes.size(); ++k) {
        const Cause& c = rep->causes[k];
        got += c.effect + " ";
        if (c.effect != kPhantom) continue;
        ++named;
        if (k == 0) ++first;
        const double f = c.parameters.at("phantom_force");
        if (k == 0 && std::abs(f - pc.force) <= 0.05 + 0.2 * pc.force)
          why.clear();
        else
          why = "force " + std::to_string(f) + " want " + std::to_string(pc.force) + " (rank " +
                std::to_string(k + 1) + ")";
      }
    if (why.empty()) {
      ++correct;
    } else {
      std::lock_guard<std::mutex> lock(mu);
      fails.push_back("seed " + std::to_string(seed) + ": " + why + "; named " +
                      (got.empty() ? "nothing" : got));
    }
  });
  Report("[phantom] named (any rank)", named, a.seeds, {});
  Report("[phantom] named first", first, a.seeds, {});
  Report("[phantom] named first + phantom_force within 0.05 N + 20 %", correct, a.seeds, fails);
}

// Seed index i of effect e: 3000000 + 100000 floor(i / 1000) + 1000 e + i mod 1000
// (indices 0-999 as before; 1000-1999 a disjoint range for every effect).
uint64_t LateSeed(Effect e, int i) {
  return 3000000 + 100000 * static_cast<uint64_t>(i / 1000) + 1000 * static_cast<int>(e) + i % 1000;
}

// For a late saturation: how much of the last third's force lies above the
// level ("" for other effects), the evidence there is to find.
std::string LateSaturationNote(const testing::HiddenCase& hc) {
  const double level = hc.model.effects.saturation;
  if (level <= 0) return "";
  const auto& t = hc.data.t;
  const double t_switch = t.front() + (t.back() - t.front()) * 2.0 / 3.0;
  double peak = 0;
  int above = 0, late = 0;
  for (size_t i = 0; i < t.size(); ++i)
    if (t[i] >= t_switch) {
      ++late;
      peak = std::max(peak, hc.data.reference[i]);
      above += hc.data.reference[i] > level;
    }
  return "  [late peak " + std::to_string(peak) + " N, level " + std::to_string(level) + " N, " +
         std::to_string(above) + "/" + std::to_string(late) + " late samples above]";
}

void LateEffects(const Args& a) {
  int all_named = 0, total = 0;
  for (Effect e : AllEffects()) {
    if (!a.effect.empty() && EffectName(e) != a.effect) continue;
    std::atomic<int> named{0}, first{0}, param{0}, last_block{0};
    std::mutex mu;
    std::vector<std::string> fails;
    ForSeeds(a.seeds, [&](int i) {
      const uint64_t seed = LateSeed(e, a.first_seed + i);
      auto hc = testing::MakeLateCase(e, seed);
      AuditOptions o = FastOptions(hc);
      o.blocks = a.blocks;
      auto rep = RunAudit(hc.data, o);
      std::string got;
      bool found = false;
      if (rep.ok())
        for (size_t k = 0; k < rep->causes.size(); ++k) {
          const Cause& c = rep->causes[k];
          got += c.effect + "(" + c.found_by + ") ";
          if (c.effect != EffectName(e) || found) continue;
          found = true;
          ++named;
          if (k == 0) ++first;
          if (testing::CheckParameters(e, hc.model.effects, c).ok) ++param;
          if (!c.blocks.empty() && c.blocks.back() == a.blocks) ++last_block;
        }
      if (!found) {
        std::lock_guard<std::mutex> lock(mu);
        fails.push_back("seed " + std::to_string(seed) + ": named " +
                        (got.empty() ? "nothing" : got) + LateSaturationNote(hc));
      }
    });
    std::cout << "[late " << EffectName(e) << "] named " << named << "/" << a.seeds << ", first "
              << first << ", parameter within tolerance " << param << ", last block shows it "
              << last_block << "\n";
    for (const auto& f : fails) std::cout << "    " << f << "\n";
    all_named += named;
    total += a.seeds;
  }
  Report("[late, all eight effects] named", all_named, total, {});
}

}  // namespace
}  // namespace tactforce::audit

static bool ParseEffectOk(const std::string& v) {
  if (tactforce::audit::ParseEffect(v).ok()) return true;
  std::cerr << "--effect: unknown effect " << v << "\n";
  std::exit(2);
}

int main(int argc, char** argv) {
  tactforce::audit::Args a;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i], v = argv[i + 1];
    if (k == "--seeds")
      a.seeds = std::atoi(v.c_str());
    else if (k == "--first-seed")
      a.first_seed = std::atoi(v.c_str());
    else if (k == "--blocks")
      a.blocks = std::atoi(v.c_str());
    else if (k == "--suite")
      a.suite = v;
    else if (k == "--seed")
      a.seed = std::atoll(v.c_str());
    else if (k == "--effect" && ParseEffectOk(v))
      a.effect = v;
    else if (k == "--effect2" && ParseEffectOk(v))
      a.effect2 = v;
    else {
      std::cerr << "unknown flag " << k << "\n";
      return 2;
    }
  }
  if (a.seeds < 1) {
    std::cerr << "--seeds: must be >= 1\n";
    return 2;
  }
  std::cout << "audit_hidden_eval: " << a.seeds << " seeds, blocks " << a.blocks << "\n";
  a.late = a.suite == "one-late";
  if (a.suite == "one" || a.late) tactforce::audit::One(a);
  if (a.suite == "partial" || a.suite == "all") tactforce::audit::PartialActivation(a);
  if (a.suite == "phantom" || a.suite == "all") tactforce::audit::Phantom(a);
  if (a.suite == "late" || a.suite == "all") tactforce::audit::LateEffects(a);
  return 0;
}
