// The effect vocabulary of the audit (names, the fields each effect owns) and
// the parameter space the fits search: per effect, its sensor-model fields
// with bounds and coarse start grids scaled by the measured run (force range,
// duration, time step; the README's candidate table), the two forms of
// hysteresis and nonlinearity, BIC's parameter count, and the values a fitted
// effect reports.
#include "effect_space.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "audit_internal.h"

namespace tactforce::audit {

const char* EffectName(Effect e) {
  switch (e) {
    case Effect::kDeadzone:
      return "deadzone";
    case Effect::kSaturation:
      return "saturation";
    case Effect::kNonlinearity:
      return "nonlinearity";
    case Effect::kHysteresis:
      return "hysteresis";
    case Effect::kDelay:
      return "delay";
    case Effect::kLag:
      return "lag";
    case Effect::kDrift:
      return "drift";
    case Effect::kCrosstalk:
      return "crosstalk";
  }
  return "?";
}

const std::vector<Effect>& AllEffects() {
  static const std::vector<Effect> all = {
      Effect::kDeadzone, Effect::kSaturation, Effect::kNonlinearity, Effect::kHysteresis,
      Effect::kDelay,    Effect::kLag,        Effect::kDrift,        Effect::kCrosstalk};
  return all;
}

std::vector<std::string> AllEffectNames() {
  std::vector<std::string> names;
  for (Effect e : AllEffects()) names.push_back(EffectName(e));
  names.push_back(kPartialActivation);
  names.push_back(kPhantom);
  return names;
}

absl::StatusOr<Effect> ParseEffect(const std::string& name) {
  for (Effect e : AllEffects())
    if (name == EffectName(e)) return e;
  return absl::InvalidArgumentError(absl::StrCat("effect: unknown '", name,
                                                 "' (expected deadzone, saturation, nonlinearity, "
                                                 "hysteresis, delay, lag, drift or crosstalk)"));
}

std::vector<std::string> EffectFields(Effect e) {
  internal::RunStats st{0, 1, 1, 1, 1, 0.01, true};
  std::vector<std::string> out;
  for (const internal::Slot& s : internal::SlotsFor(e, st, AuditOptions{})) out.push_back(s.field);
  // The second forms' fields.
  if (e == Effect::kHysteresis) {
    out.push_back("pi_thresholds");
    out.push_back("pi_weights");
  }
  if (e == Effect::kNonlinearity) {
    out.push_back("power_exponent");
    out.push_back("full_scale");
  }
  return out;
}

namespace internal {

using sim::EffectParams;

RunStats ComputeRunStats(const MeasuredData& data) {
  RunStats st;
  auto [lo, hi] = std::minmax_element(data.reference.begin(), data.reference.end());
  st.fmin = *lo;
  st.fmax = *hi;
  st.range = st.fmax - st.fmin;
  st.fabsmax = std::max(std::abs(st.fmin), std::abs(st.fmax));
  st.duration = data.t.back() - data.t.front();
  st.dt = MedianStep(data.t, 1.0);
  st.has_shear = !data.shear.empty();
  return st;
}

double Get(const EffectParams& p, const Slot& s) {
  return s.pi_index >= 0 ? p.pi_weights[s.pi_index] : p.*(s.ptr);
}

void Set(EffectParams& p, const Slot& s, double v) {
  if (s.pi_index >= 0)
    p.pi_weights[s.pi_index] = v;
  else
    p.*(s.ptr) = v;
}

const char* FormName(Form f) {
  switch (f) {
    case Form::kOnly:
      return "";
    case Form::kPlay:
      return "play";
    case Form::kPrandtlIshlinskii:
      return "prandtl_ishlinskii";
    case Form::kQuadratic:
      return "quadratic";
    case Form::kPowerLaw:
      return "power_law";
  }
  return "";
}

Form DefaultForm(Effect e) {
  if (e == Effect::kHysteresis) return Form::kPlay;
  if (e == Effect::kNonlinearity) return Form::kQuadratic;
  return Form::kOnly;
}

Form FormOf(Effect e, const EffectParams& p) {
  if (e == Effect::kHysteresis)
    return p.pi_thresholds.empty() ? Form::kPlay : Form::kPrandtlIshlinskii;
  if (e == Effect::kNonlinearity) return p.power_exponent > 0 ? Form::kPowerLaw : Form::kQuadratic;
  return Form::kOnly;
}

std::vector<double> GeometricGrid(double a, double b, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = a * std::pow(b / a, n == 1 ? 0.0 : double(i) / (n - 1));
  return v;
}

std::vector<double> LinearGrid(double a, double b, int n) {
  std::vector<double> v(n);
  for (int i = 0; i < n; ++i) v[i] = a + (b - a) * (n == 1 ? 0.0 : double(i) / (n - 1));
  return v;
}

bool IsSmooth(Effect e) {
  return e == Effect::kNonlinearity || e == Effect::kDrift || e == Effect::kCrosstalk;
}

namespace {

// The slots of the effects with one slot grid each (every form but PI and
// the power law).
std::vector<Slot> DefaultSlots(Effect e, const RunStats& s, const AuditOptions& o) {
  const double R = s.range;
  switch (e) {
    case Effect::kDeadzone: {
      std::vector<double> g;
      for (double x : GeometricGrid(0.003 * R, 0.5 * R, 24)) g.push_back(s.fmin + x);
      return {{"threshold", &EffectParams::threshold, std::max(0.0, s.fmin), s.fmin + 0.5 * R, g},
              {"threshold_shift", &EffectParams::threshold_shift, 0, 1, {0, 1}}};
    }
    case Effect::kSaturation:
      return {{"saturation", &EffectParams::saturation, s.fmin + 0.2 * R, s.fmax,
               LinearGrid(s.fmin + 0.2 * R, s.fmax, 24)}};
    case Effect::kNonlinearity:
      return {{"curvature", &EffectParams::curvature, -0.5, 0.5, LinearGrid(-0.3, 0.3, 7)}};
    case Effect::kHysteresis:
      return {{"hysteresis_width", &EffectParams::hysteresis_width, 0, 0.3 * R,
               GeometricGrid(0.002 * R, 0.3 * R, 24)}};
    case Effect::kDelay: {
      std::vector<double> g;
      const double lo = std::min(0.25 * s.dt, 0.5 * o.max_delay);
      for (double x : GeometricGrid(lo, o.max_delay, 12)) {
        g.push_back(x);
        g.push_back(-x);
      }
      g.push_back(0);
      std::sort(g.begin(), g.end());
      return {{"delay", &EffectParams::delay, -o.max_delay, o.max_delay, g}};
    }
    case Effect::kLag: {
      const double lo = std::min(0.25 * s.dt, 0.5 * o.max_lag);
      return {{"lag", &EffectParams::lag, 0, o.max_lag, GeometricGrid(lo, o.max_lag, 24)}};
    }
    case Effect::kDrift: {
      const double m = R / std::max(s.duration, 1e-9);
      return {{"drift", &EffectParams::drift, -m, m, LinearGrid(-0.3 * m, 0.3 * m, 7)}};
    }
    case Effect::kCrosstalk:
      return {{"crosstalk", &EffectParams::crosstalk, -1, 1, LinearGrid(-0.6, 0.6, 7)}};
  }
  return {};
}

}  // namespace

std::vector<Slot> SlotsFor(Effect e, const RunStats& s, const AuditOptions& o, Form form,
                           const EffectParams* p) {
  if (form == Form::kPowerLaw)
    return {{"power_exponent",
             &EffectParams::power_exponent,
             0.2,
             4.0,
             {0.5, 0.67, 0.8, 0.9, 1.1, 1.25, 1.5, 2.0}}};
  if (form == Form::kPrandtlIshlinskii) {
    std::vector<Slot> v;
    if (p)
      for (size_t k = 0; k < p->pi_weights.size(); ++k)
        v.push_back(
            {absl::StrCat("pi_weights[", k, "]"), nullptr, 0.0, 1.0, {}, static_cast<int>(k)});
    return v;
  }
  return DefaultSlots(e, s, o);
}

std::vector<Slot> SelectedSlots(const std::vector<Effect>& selected, const EffectParams& p,
                                const RunStats& st, const AuditOptions& o, bool* smooth) {
  std::vector<Slot> v;
  for (Effect s : selected) {
    const Form f = FormOf(s, p);
    for (Slot& sl : SlotsFor(s, st, o, f, &p)) v.push_back(std::move(sl));
    // PI weights enter non-smoothly through the play operators.
    if (smooth) *smooth = *smooth && IsSmooth(s) && f != Form::kPrandtlIshlinskii;
  }
  return v;
}

int NumParams(Effect e, const EffectParams& p) {
  if (e == Effect::kDeadzone) return 2;
  if (e == Effect::kHysteresis && !p.pi_thresholds.empty())
    return static_cast<int>(p.pi_thresholds.size());
  return 1;
}

double Bic(double rss, int n, int k) {
  return n * std::log(std::max(rss, 1e-300) / n) + k * std::log(static_cast<double>(n));
}

void NormaliseWeights(std::vector<double>* weights) {
  double ws = 0;
  for (double w : *weights) ws += w;
  if (ws > 0)
    for (double& w : *weights) w /= ws;
}

namespace {

// Maximal loop width of a PI hysteresis (normalised weights): 2 sum w_k r_k.
double PiLoopWidth(const EffectParams& p) {
  double ws = 0, wr = 0;
  for (size_t k = 0; k < p.pi_weights.size() && k < p.pi_thresholds.size(); ++k) {
    ws += p.pi_weights[k];
    wr += p.pi_weights[k] * p.pi_thresholds[k];
  }
  return ws > 0 ? 2 * wr / ws : 0;
}

}  // namespace

std::map<std::string, double> ParamsOf(Effect e, const EffectParams& p, const RunStats& st,
                                       const AuditOptions& o) {
  std::map<std::string, double> m;
  const Form f = FormOf(e, p);
  if (f == Form::kPrandtlIshlinskii) {
    m["loop_width"] = PiLoopWidth(p);
    m["operators"] = static_cast<double>(p.pi_thresholds.size());
    return m;
  }
  for (const Slot& s : SlotsFor(e, st, o, f, &p)) m[s.field] = Get(p, s);
  if (e == Effect::kNonlinearity) m["full_scale"] = p.full_scale;
  return m;
}

std::map<std::string, std::vector<double>> ArrayParamsOf(Effect e, const EffectParams& p) {
  std::map<std::string, std::vector<double>> m;
  if (FormOf(e, p) == Form::kPrandtlIshlinskii) {
    m["pi_thresholds"] = p.pi_thresholds;
    std::vector<double> w = p.pi_weights;
    NormaliseWeights(&w);
    m["pi_weights"] = w;
  }
  return m;
}

}  // namespace internal
}  // namespace tactforce::audit
