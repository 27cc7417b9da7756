// Hidden-effect generator for the audit tests: per seed, one (or two)
// effect types with parameters drawn from ranges that matter, simulated on a
// press-release profile with GeoDEx-like noise, in N or in counts (random
// sign and scale of the gain). Deterministic in the seed.
#pragma once

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <iostream>
#include <algorithm>
#include <atomic>
#include <random>
#include <thread>
#include <string>
#include <vector>

#include "tactforce/audit/audit.h"
#include "tactforce/sim/simulate.h"

namespace tactforce::audit::testing {

struct HiddenCase {
  std::vector<Effect> effects;  // empty = null case
  sim::SensorModel model;       // the truth
  sim::SimOptions sim;
  MeasuredData data;
};

inline constexpr double kMaxPeak = 8.0;

// The seed of the cases drawn at test time: TACTFORCE_TEST_SEED or a random
// one, printed so that a failure can be repeated.
inline uint64_t TestSeed() {
  static const uint64_t seed = [] {
    const char* env = std::getenv("TACTFORCE_TEST_SEED");
    const uint64_t s = env ? std::strtoull(env, nullptr, 10) : std::random_device{}();
    std::cout << "[ seed ] TACTFORCE_TEST_SEED=" << s << "\n";
    return s;
  }();
  return seed;
}

// Audit options for the many-seed tests: no downstream gain, no
// uncertainties (the expensive extras), the case's reading units.
inline AuditOptions FastOptions(const HiddenCase& hc) {
  AuditOptions o;
  o.downstream_gain = false;
  o.uncertainties = false;
  o.reading_units = hc.model.units;
  return o;
}

// Runs body(i) for i in [0, n) on two threads.
template <typename F>
void ForSeeds(int n, F body) {
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int i = next++; i < n; i = next++) body(i);
  };
  std::thread a(worker), b(worker);
  a.join();
  b.join();
}

// Which form of a two-form effect to hide (kDefault: play operator for
// hysteresis, quadratic for nonlinearity).
enum class HiddenForm { kDefault, kPrandtlIshlinskii, kPowerLaw };

// Prandtl-Ishlinskii: the identity (r = 0) with weight 0.1-0.5 plus 3-5 play
// operators with radii log-uniform in [0.03, 0.3] N, weights uniform in
// [0.2, 1] (relative); all normalised to sum 1.
inline void DrawPrandtlIshlinskii(std::mt19937_64& rng, sim::EffectParams* p) {
  auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const int K = 3 + static_cast<int>(uni(0, 3));
  std::vector<double> r;
  while (static_cast<int>(r.size()) < K) {
    const double v = 0.03 * std::pow(10.0, uni(0, 1));
    bool distinct = true;
    for (double x : r) distinct = distinct && std::abs(std::log(x / v)) > 0.05;
    if (distinct) r.push_back(v);
  }
  std::sort(r.begin(), r.end());
  const double w0 = uni(0.1, 0.5);
  std::vector<double> w;
  double ws = 0;
  for (int k = 0; k < K; ++k) {
    w.push_back(uni(0.2, 1.0));
    ws += w.back();
  }
  p->pi_thresholds = {0.0};
  p->pi_weights = {w0};
  for (int k = 0; k < K; ++k) {
    p->pi_thresholds.push_back(r[k]);
    p->pi_weights.push_back((1 - w0) * w[k] / ws);
  }
}

// Maximal loop width of a PI hysteresis, 2 sum w_k r_k / sum w_k (N).
inline double PiLoopWidth(const sim::EffectParams& p) {
  double ws = 0, wr = 0;
  for (size_t k = 0; k < p.pi_weights.size(); ++k) {
    ws += p.pi_weights[k];
    wr += p.pi_weights[k] * p.pi_thresholds[k];
  }
  return ws > 0 ? 2 * wr / ws : 0;
}

// Parameter ranges (documented in the README's audit section).
inline void DrawEffect(Effect e, std::mt19937_64& rng, double seconds, sim::EffectParams* p,
                       HiddenForm form = HiddenForm::kDefault) {
  auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  auto sign = [&]() { return uni(0, 1) < 0.5 ? -1.0 : 1.0; };
  if (e == Effect::kHysteresis && form == HiddenForm::kPrandtlIshlinskii)
    return DrawPrandtlIshlinskii(rng, p);
  if (e == Effect::kNonlinearity && form == HiddenForm::kPowerLaw) {
    // Power law reading = a F^p + b: p in [0.7, 0.95] or [1.05, 1.4].
    p->power_exponent = uni(0, 1) < 0.5 ? uni(0.7, 0.95) : uni(1.05, 1.4);
    p->full_scale = kMaxPeak;
    return;
  }
  switch (e) {
    case Effect::kDeadzone:
      p->threshold = uni(0.1, 0.5);
      p->threshold_shift = uni(0, 1) < 0.5 ? 0.0 : 1.0;  // activation jump or continuous dead-zone
      break;
    case Effect::kSaturation:
      p->saturation = uni(0.4, 0.8);  // x the run's peak force (see MakeHiddenCase)
      break;
    case Effect::kNonlinearity:
      p->curvature = sign() * uni(0.02, 0.08);
      p->full_scale = kMaxPeak;
      break;
    case Effect::kHysteresis:
      p->hysteresis_width = uni(0.05, 0.3);
      break;
    case Effect::kDelay:
      p->delay = uni(0.010, 0.100);
      break;
    case Effect::kLag:
      p->lag = uni(0.010, 0.100);
      break;
    case Effect::kDrift:
      p->drift = sign() * uni(0.1, 0.5) / seconds;
      break;
    case Effect::kCrosstalk:
      p->crosstalk = sign() * uni(0.05, 0.3);
      break;
  }
}

inline HiddenCase MakeHiddenCase(const std::vector<Effect>& effects, uint64_t seed,
                                 HiddenForm form = HiddenForm::kDefault) {
  std::mt19937_64 rng(seed * 7919 + 17);
  auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  HiddenCase hc;
  hc.effects = effects;
  hc.sim.profile = sim::Profile::kPressRelease;
  hc.sim.rate = uni(100, 500);
  hc.sim.seconds = std::max(10.0, 2500 / hc.sim.rate);
  hc.sim.seed = seed;
  hc.sim.min_peak = 1.0;
  hc.sim.max_peak = kMaxPeak;
  sim::SensorModel& m = hc.model;
  m.noise = uni(0.01, 0.03);
  if (uni(0, 1) < 0.5) {
    m.units = "N";
  } else {
    m.units = "counts";
    m.gain = (uni(0, 1) < 0.5 ? -1 : 1) * uni(20, 80);
    m.offset = uni(500, 1500);
  }
  for (Effect e : effects) DrawEffect(e, rng, hc.sim.seconds, &m.effects, form);
  if (m.effects.saturation > 0) {
    // Saturation inside the run's force range: a fraction of its peak force
    // (the profile does not depend on the model, only on the seed).
    auto ideal = sim::SimulateSensor(sim::SensorModel{}, hc.sim);
    double fmax = 0;
    if (ideal.ok())
      for (double f : ideal->true_force) fmax = std::max(fmax, f);
    m.effects.saturation *= fmax;
  }
  auto run = sim::SimulateSensor(m, hc.sim);
  if (!run.ok()) return hc;
  auto data = ParseMeasuredCsv(sim::SimRunCsv(*run), "hidden.csv");
  if (data.ok()) hc.data = *data;
  return hc;
}

// Tolerances on the recovered parameter (documented in the README).
struct Recovery {
  bool ok = false;
  std::string what;
};

inline Recovery CheckParameters(Effect e, const sim::EffectParams& truth, const Cause& c) {
  auto get = [&](const char* k) {
    auto it = c.parameters.find(k);
    return it == c.parameters.end() ? NAN : it->second;
  };
  auto within = [](double got, double want, double abs_tol, double rel_tol) {
    return std::abs(got - want) <= abs_tol + rel_tol * std::abs(want);
  };
  Recovery r;
  double got = NAN, want = NAN;
  const char* name = "";
  // An effect recovered as the one parameter `key`, within abs_tol + rel_tol |truth|.
  auto plain = [&](const char* key, double truth_value, double abs_tol, double rel_tol) {
    name = key;
    got = get(name);
    want = truth_value;
    r.ok = within(got, want, abs_tol, rel_tol);
  };
  switch (e) {
    case Effect::kDeadzone:
      plain("threshold", truth.threshold, 0.03, 0.15);
      break;
    case Effect::kSaturation:
      plain("saturation", truth.saturation, 0.05, 0.03);
      break;
    case Effect::kNonlinearity: {
      if (truth.power_exponent > 0) {
        // Power law: the exponent, +/-(0.01 + 2 %).
        name = "power_exponent";
        got = get(name);
        want = truth.power_exponent;
        r.ok = within(got, want, 0.01, 0.02);
        break;
      }
      name = "curvature";
      // Curvature is relative to full_scale: compare the coefficient c / F.
      got = get("curvature") / get("full_scale") * truth.full_scale;
      want = truth.curvature;
      r.ok = within(got, want, 0.005, 0.2);
      break;
    }
    case Effect::kHysteresis:
      if (!truth.pi_thresholds.empty()) {
        // PI truth: the maximal loop width 2 sum w r, +/-(0.03 N + 20 %),
        // from whichever form was named (play: its width).
        name = "loop_width";
        got = c.form == "play" ? get("hysteresis_width") : get("loop_width");
        want = PiLoopWidth(truth);
        r.ok = within(got, want, 0.03, 0.2);
        break;
      }
      // Play truth: the width, from the play form or the PI's loop width.
      name = "hysteresis_width";
      got = c.form == "prandtl_ishlinskii" ? get("loop_width") : get(name);
      want = truth.hysteresis_width;
      r.ok = within(got, want, 0.02, 0.15);
      break;
    case Effect::kDelay:
      plain("delay", truth.delay, 0.002, 0.1);
      break;
    case Effect::kLag:
      plain("lag", truth.lag, 0.003, 0.15);
      break;
    case Effect::kDrift:
      plain("drift", truth.drift, 0.002, 0.2);
      break;
    case Effect::kCrosstalk:
      plain("crosstalk", truth.crosstalk, 0.01, 0.1);
      break;
  }
  r.what = std::string(name) + " got " + std::to_string(got) + " want " + std::to_string(want);
  return r;
}

// ---- issue 26: late-only effects, phantom forces, per-taxel data ----------

// A single effect that appears only in the last third of the run: the
// reading is the effect-free sensor's (same gain, offset, noise seed) before
// t0 + 2/3 of the duration and the sensor with the effect after (a drift
// starts from zero there).
inline HiddenCase MakeLateCase(Effect e, uint64_t seed) {
  HiddenCase hc = MakeHiddenCase({e}, seed);
  sim::SensorModel clean = hc.model;
  clean.effects = sim::EffectParams{};
  auto with = sim::SimulateSensor(hc.model, hc.sim);
  auto without = sim::SimulateSensor(clean, hc.sim);
  if (!with.ok() || !without.ok()) return hc;
  const double t0 = without->t.front(), t_switch = t0 + (without->t.back() - t0) * 2.0 / 3.0;
  for (size_t i = 0; i < without->t.size(); ++i)
    if (without->t[i] >= t_switch)
      without->reading[i] =
          with->reading[i] - hc.model.gain * hc.model.effects.drift * (t_switch - t0);
  auto data = ParseMeasuredCsv(sim::SimRunCsv(*without), "late.csv");
  if (data.ok()) hc.data = *data;
  return hc;
}

// The phantom the audit names (audit.h): exp(-(t - t_r)/decay) at every
// sample whose reference is <= release after a loaded sample, t_r the first
// such sample; written here independently of the audit's code.
inline std::vector<double> PhantomShape(const std::vector<double>& t, const std::vector<double>& f,
                                        double release, double decay) {
  std::vector<double> out(t.size(), 0.0);
  bool loaded = false;
  double t_release = -1;
  for (size_t i = 0; i < t.size(); ++i) {
    if (f[i] > release) {
      loaded = true;
      t_release = -1;
    } else if (loaded) {
      if (t_release < 0) t_release = t[i];
      out[i] = std::exp(-(t[i] - t_release) / decay);
    }
  }
  return out;
}

struct PhantomCase {
  HiddenCase hc;
  double force = 0, decay = 0;  // N, s (truth)
};

// A phantom force of 0.2-1 N decaying with 0.3-3 s after every release, on
// top of the press-release run of MakeHiddenCase (no other effect).
inline PhantomCase MakePhantomCase(uint64_t seed) {
  PhantomCase pc;
  pc.hc = MakeHiddenCase({}, seed);
  std::mt19937_64 rng(seed * 104729 + 3);
  pc.force = std::uniform_real_distribution<double>(0.2, 1.0)(rng);
  pc.decay = std::uniform_real_distribution<double>(0.3, 3.0)(rng);
  auto run = sim::SimulateSensor(pc.hc.model, pc.hc.sim);
  if (!run.ok()) return pc;
  auto [lo, hi] = std::minmax_element(run->reference.begin(), run->reference.end());
  const auto shape = PhantomShape(run->t, run->reference, *lo + 0.05 * (*hi - *lo), pc.decay);
  for (size_t i = 0; i < shape.size(); ++i)
    run->reading[i] += pc.hc.model.gain * pc.force * shape[i];
  auto data = ParseMeasuredCsv(sim::SimRunCsv(*run), "phantom.csv");
  if (data.ok()) pc.hc.data = *data;
  return pc;
}

// Per-taxel data: the 42-taxel fingertip of sim/ (DefaultFingertip) pressed
// at every taxel once, in a random order (a calibration sweep): per press a
// peak of 4-8 N (ramp 0.25 s, hold 0.1 s, release 0.25 s, rest 0.15 s); each
// taxel's load = the force x its share of a Gaussian patch of radius
// 3 mm + 1.5 mm sqrt(F / 1 N) around the pressed taxel, weighted by the
// cosine between the normals (shares sum to 1). Each taxel has its own draw
// (GeoDEx's ranges): activation threshold 0.1-0.5 N (a jump), hysteresis
// 0-0.2 N, noise 0.01-0.03 N; half the cases in counts (per-taxel gain 0.9-1.1
// x 20-80 /N, offset 500-1500). `dead` taxels (drawn) read only their offset
// and noise. 100-200 Hz.
struct TaxelCase {
  MeasuredData data;
  std::vector<int> dead;  // taxel indices that never activate
  int taxels = 0;
  std::string csv;  // the CSV text (t,reference,taxel_0..)
};

inline TaxelCase MakeTaxelCase(uint64_t seed, int dead_count) {
  std::mt19937_64 rng(seed * 6007 + 11);
  auto uni = [&](double a, double b) { return std::uniform_real_distribution<double>(a, b)(rng); };
  const auto tips = sim::DefaultFingertip();
  const int m = static_cast<int>(tips.size());
  TaxelCase tc;
  tc.taxels = m;
  std::vector<int> order(m);
  for (int j = 0; j < m; ++j) order[j] = j;
  std::shuffle(order.begin(), order.end(), rng);
  tc.dead.assign(order.begin(), order.begin() + dead_count);
  std::shuffle(order.begin(), order.end(), rng);
  const double rate = uni(100, 200), press = 0.75;
  const int per_press = static_cast<int>(press * rate);
  const int n = per_press * m + static_cast<int>(0.3 * rate);
  std::vector<double> t(n), force(n, 0.0);
  std::vector<std::vector<double>> load(m, std::vector<double>(n, 0.0));
  for (int i = 0; i < n; ++i) t[i] = i / rate;
  for (int k = 0; k < m; ++k) {
    const double peak = uni(4, 8);
    const int c = order[k];
    for (int q = 0; q < per_press; ++q) {
      const double tau = q / rate;
      const double f = tau < 0.25   ? peak * tau / 0.25
                       : tau < 0.35 ? peak
                       : tau < 0.6  ? peak * (0.6 - tau) / 0.25
                                    : 0;
      const int i = k * per_press + q + static_cast<int>(0.15 * rate);
      force[i] = f;
      if (f <= 0) continue;
      const double a = 0.003 + 0.0015 * std::sqrt(f);
      std::vector<double> w(m);
      double ws = 0;
      for (int j = 0; j < m; ++j) {
        const double d2 = (tips[j].position - tips[c].position).squaredNorm();
        w[j] = std::exp(-d2 / (2 * a * a)) * std::max(0.0, tips[j].normal.dot(tips[c].normal));
        ws += w[j];
      }
      for (int j = 0; j < m; ++j) load[j][i] = f * w[j] / ws;
    }
  }
  const bool counts = uni(0, 1) < 0.5;
  const double base_gain = counts ? uni(20, 80) : 1.0;
  std::normal_distribution<double> gauss(0, 1);
  std::string csv = "t,reference";
  for (int j = 0; j < m; ++j) csv += ",taxel_" + std::to_string(j);
  csv += "\n";
  std::vector<std::vector<double>> reading(m, std::vector<double>(n));
  for (int j = 0; j < m; ++j) {
    sim::EffectParams p;
    p.threshold = uni(0.1, 0.5);
    p.hysteresis_width = uni(0, 0.2);
    const double noise = uni(0.01, 0.03), gain = counts ? base_gain * uni(0.9, 1.1) : 1.0;
    const double offset = counts ? uni(500, 1500) : 0.0;
    const bool dead = std::find(tc.dead.begin(), tc.dead.end(), j) != tc.dead.end();
    std::vector<double> u(n, 0.0);
    if (!dead) {
      sim::ChannelInput in;
      in.t = t.data();
      in.force = load[j].data();
      in.n = n;
      in.t0 = 0;
      sim::ApplyChannel(p, in, &u);
    }
    for (int i = 0; i < n; ++i) reading[j][i] = gain * (u[i] + noise * gauss(rng)) + offset;
  }
  for (int i = 0; i < n; ++i) {
    csv += std::to_string(t[i]) + "," + std::to_string(force[i]);
    for (int j = 0; j < m; ++j) csv += "," + std::to_string(reading[j][i]);
    csv += "\n";
  }
  auto data = ParseMeasuredCsv(csv, "taxels.csv");
  if (data.ok()) tc.data = *data;
  tc.csv = std::move(csv);
  return tc;
}

}  // namespace tactforce::audit::testing
