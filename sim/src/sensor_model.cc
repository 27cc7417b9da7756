// The sensor model: its JSON form (read with file:line errors naming the
// field, validated, written), the force-domain channel ApplyChannel that the
// simulation and the audit share (crosstalk; per segment delay, lag and
// hysteresis; then the static effects and drift), the noise-free reading of
// a measured reference (PredictReading) and the static inverse used to
// correct readings (CorrectReading).
#include "tactforce/sim/sensor_model.h"

#include <algorithm>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "tactforce/io/json.h"
#include "tactforce/io/suggest.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::sim {
namespace {

constexpr char kFormat[] = "tactforce.sensor_model.v1";

struct NumField {
  const char* name;
  double SensorModel::*model_field;  // or null
  double EffectParams::*effect_field;
};

const std::vector<NumField>& NumFields() {
  static const std::vector<NumField> f = {
      {"gain", &SensorModel::gain, nullptr},
      {"offset", &SensorModel::offset, nullptr},
      {"noise", &SensorModel::noise, nullptr},
      {"partial_error", &SensorModel::partial_error, nullptr},
      {"threshold", nullptr, &EffectParams::threshold},
      {"threshold_shift", nullptr, &EffectParams::threshold_shift},
      {"hysteresis_width", nullptr, &EffectParams::hysteresis_width},
      {"delay", nullptr, &EffectParams::delay},
      {"lag", nullptr, &EffectParams::lag},
      {"saturation", nullptr, &EffectParams::saturation},
      {"curvature", nullptr, &EffectParams::curvature},
      {"full_scale", nullptr, &EffectParams::full_scale},
      {"drift", nullptr, &EffectParams::drift},
      {"crosstalk", nullptr, &EffectParams::crosstalk},
      {"power_exponent", nullptr, &EffectParams::power_exponent},
  };
  return f;
}

double& FieldRef(SensorModel& m, const NumField& f) {
  return f.model_field ? m.*(f.model_field) : m.effects.*(f.effect_field);
}
double FieldVal(const SensorModel& m, const NumField& f) {
  return f.model_field ? m.*(f.model_field) : m.effects.*(f.effect_field);
}
// Every key a sensor-model JSON may have, for "did you mean" suggestions.
std::vector<std::string> ModelKeys() {
  std::vector<std::string> keys = {"format",      "units",         "source",
                                   "uncertainty", "pi_thresholds", "pi_weights"};
  for (const auto& f : NumFields()) keys.emplace_back(f.name);
  return keys;
}

bool IsField(std::string_view name) {
  for (const auto& f : NumFields())
    if (name == f.name) return true;
  return false;
}

constexpr size_t kMaxPiOperators = 64;

// Uncertainty keys: the numeric fields plus "pi_weights[k]" / "pi_thresholds[k]".
bool IsUncertaintyKey(std::string_view name) {
  if (IsField(name)) return true;
  for (std::string_view prefix :
       {std::string_view("pi_weights["), std::string_view("pi_thresholds[")}) {
    if (name.size() > prefix.size() + 1 && name.substr(0, prefix.size()) == prefix &&
        name.back() == ']') {
      std::string_view digits = name.substr(prefix.size(), name.size() - prefix.size() - 1);
      if (!digits.empty() &&
          std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; }))
        return true;
    }
  }
  return false;
}

}  // namespace

absl::Status ValidateSensorModel(const SensorModel& m) {
  for (const auto& f : NumFields()) {
    if (!std::isfinite(FieldVal(m, f)))
      return absl::InvalidArgumentError(
          absl::StrCat("model field '", f.name, "': not a finite number"));
  }
  auto nonneg = [](double v, const char* name) -> absl::Status {
    if (v < 0)
      return absl::InvalidArgumentError(
          absl::StrCat("model field '", name, "': must be >= 0, got ", v));
    return absl::OkStatus();
  };
  const EffectParams& e = m.effects;
  if (m.gain == 0) return absl::InvalidArgumentError("model field 'gain': must be non-zero");
  for (auto st : {nonneg(m.noise, "noise"), nonneg(m.partial_error, "partial_error"),
                  nonneg(e.threshold, "threshold"), nonneg(e.hysteresis_width, "hysteresis_width"),
                  nonneg(e.lag, "lag"), nonneg(e.saturation, "saturation")})
    TF_RETURN_IF_ERROR(st);
  if (e.threshold_shift < 0 || e.threshold_shift > 1)
    return absl::InvalidArgumentError(
        absl::StrCat("model field 'threshold_shift': must be in [0, 1], got ", e.threshold_shift));
  if (e.full_scale <= 0)
    return absl::InvalidArgumentError(
        absl::StrCat("model field 'full_scale': must be > 0, got ", e.full_scale));
  if (std::abs(e.delay) > 10)
    return absl::InvalidArgumentError(
        absl::StrCat("model field 'delay': |delay| must be <= 10 s, got ", e.delay));
  if (e.lag > 10)
    return absl::InvalidArgumentError(
        absl::StrCat("model field 'lag': must be <= 10 s, got ", e.lag));
  if (e.power_exponent < 0 || e.power_exponent > 10)
    return absl::InvalidArgumentError(absl::StrCat(
        "model field 'power_exponent': must be in (0, 10] (0 = off), got ", e.power_exponent));
  if (e.pi_thresholds.size() != e.pi_weights.size())
    return absl::InvalidArgumentError(
        absl::StrCat("model fields 'pi_thresholds' and 'pi_weights': must have the same length (",
                     e.pi_thresholds.size(), " vs ", e.pi_weights.size(), ")"));
  if (e.pi_thresholds.size() > kMaxPiOperators)
    return absl::InvalidArgumentError(absl::StrCat("model field 'pi_thresholds': at most ",
                                                   kMaxPiOperators, " play operators, got ",
                                                   e.pi_thresholds.size()));
  if (!e.pi_thresholds.empty()) {
    if (e.hysteresis_width > 0)
      return absl::InvalidArgumentError(
          "model fields 'hysteresis_width' and 'pi_thresholds': the play operator and "
          "Prandtl-Ishlinskii hysteresis are "
          "exclusive forms; set one");
    double wsum = 0;
    for (size_t k = 0; k < e.pi_thresholds.size(); ++k) {
      const double r = e.pi_thresholds[k], w = e.pi_weights[k];
      if (!std::isfinite(r) || r < 0)
        return absl::InvalidArgumentError(absl::StrCat(
            "model field 'pi_thresholds[", k, "]': must be a finite number >= 0, got ", r));
      if (k > 0 && !(r > e.pi_thresholds[k - 1]))
        return absl::InvalidArgumentError(absl::StrCat("model field 'pi_thresholds[", k,
                                                       "]': thresholds must increase strictly (", r,
                                                       " after ", e.pi_thresholds[k - 1], ")"));
      if (!std::isfinite(w) || w < 0)
        return absl::InvalidArgumentError(absl::StrCat(
            "model field 'pi_weights[", k, "]': must be a finite number >= 0, got ", w));
      wsum += w;
    }
    if (!(wsum > 0))
      return absl::InvalidArgumentError("model field 'pi_weights': the weights must not all be 0");
  }
  for (const auto& [k, v] : m.uncertainty) {
    if (!IsUncertaintyKey(k))
      return absl::InvalidArgumentError(
          absl::StrCat("model field 'uncertainty.", k, "': unknown field"));
  }
  return absl::OkStatus();
}

absl::StatusOr<SensorModel> SensorModelFromJson(const std::string& text,
                                                const std::string& source) {
  TF_ASSIGN_OR_RETURN(auto doc, io::ParseJson(text, source));
  if (!doc.is_object())
    return absl::InvalidArgumentError(
        absl::StrCat(source, ": a sensor model must be a JSON object"));
  SensorModel m;
  m.source.clear();
  for (const auto& [key, v] : doc.members()) {
    auto where = absl::StrCat(source, ":", v.line(), ": field '", key, "'");
    if (key == "format") {
      if (!v.is_string() || v.string() != kFormat)
        return absl::InvalidArgumentError(absl::StrCat(where, ": expected \"", kFormat, "\""));
      continue;
    }
    if (key == "units" || key == "source") {
      if (!v.is_string())
        return absl::InvalidArgumentError(absl::StrCat(where, ": expected a string"));
      (key == "units" ? m.units : m.source) = v.string();
      continue;
    }
    if (key == "uncertainty") {
      if (!v.is_object())
        return absl::InvalidArgumentError(absl::StrCat(where, ": expected an object"));
      for (const auto& [uk, uv] : v.members()) {
        if (!IsUncertaintyKey(uk))
          return absl::InvalidArgumentError(absl::StrCat(
              source, ":", uv.line(), ": field 'uncertainty.", uk, "': unknown field"));
        if (uv.is_null()) continue;
        if (!uv.is_number())
          return absl::InvalidArgumentError(absl::StrCat(
              source, ":", uv.line(), ": field 'uncertainty.", uk, "': expected a number"));
        m.uncertainty[uk] = uv.number();
      }
      continue;
    }
    if (key == "effects_named" || key == "notes") continue;  // informational (audit output)
    if (key == "pi_thresholds" || key == "pi_weights") {
      if (!v.is_array())
        return absl::InvalidArgumentError(absl::StrCat(where, ": expected an array of numbers"));
      std::vector<double>& dst =
          key == "pi_thresholds" ? m.effects.pi_thresholds : m.effects.pi_weights;
      dst.clear();
      for (size_t k = 0; k < v.array().size(); ++k) {
        const io::JsonValue& x = v.array()[k];
        if (!x.is_number())
          return absl::InvalidArgumentError(absl::StrCat(source, ":", x.line(), ": field '", key,
                                                         "[", k, "]': expected a number"));
        dst.push_back(x.number());
      }
      continue;
    }
    bool found = false;
    for (const auto& f : NumFields()) {
      if (key != f.name) continue;
      found = true;
      if (!v.is_number())
        return absl::InvalidArgumentError(absl::StrCat(where, ": expected a number"));
      FieldRef(m, f) = v.number();
    }
    if (!found)
      return absl::InvalidArgumentError(
          absl::StrCat(where, ": unknown field", io::DidYouMean(key, ModelKeys())));
  }
  TF_RETURN_IF_ERROR(io::PrependPath(ValidateSensorModel(m), source));
  return m;
}

absl::StatusOr<SensorModel> LoadSensorModel(const std::string& path) {
  TF_ASSIGN_OR_RETURN(std::string text, io::ReadTextFile(path));
  return SensorModelFromJson(text, io::SourceName(path));
}

std::string SensorModelToJson(const SensorModel& m) {
  io::JsonWriter w;
  w.BeginObject();
  w.Field("format", kFormat);
  w.Field("units", m.units);
  if (!m.source.empty()) w.Field("source", m.source);
  for (const auto& f : NumFields()) w.Field(f.name, FieldVal(m, f));
  if (!m.effects.pi_thresholds.empty() || !m.effects.pi_weights.empty()) {
    w.NumberArray("pi_thresholds", m.effects.pi_thresholds);
    w.NumberArray("pi_weights", m.effects.pi_weights);
  }
  if (!m.uncertainty.empty()) {
    w.Key("uncertainty");
    w.BeginObject();
    for (const auto& [k, v] : m.uncertainty) w.Field(k, v);
    w.EndObject();
  }
  w.EndObject();
  return w.str();
}

absl::Status SaveSensorModel(const SensorModel& m, const std::string& path) {
  return io::WriteTextFile(path, SensorModelToJson(m));
}

// ---------------------------------------------------------------------------

namespace {

// Catmull-Rom interpolation of x at time tq within [lo, hi) (indices), with
// a moving cursor. Clamps outside the segment.
struct Interp {
  const double* t;
  const double* x;
  int lo, hi;  // segment [lo, hi)
  int k;       // cursor: t[k] <= tq < t[k+1]
  double operator()(double tq) {
    if (tq <= t[lo]) return x[lo];
    if (tq >= t[hi - 1]) return x[hi - 1];
    while (k + 1 < hi - 1 && t[k + 1] <= tq) ++k;
    while (k > lo && t[k] > tq) --k;
    const int i0 = k, i1 = k + 1;
    const double h = t[i1] - t[i0];
    const double s = (tq - t[i0]) / h;
    // Tangents by finite differences (non-uniform safe), one-sided at ends.
    auto slope = [&](int i) {
      if (i <= lo) return (x[lo + 1] - x[lo]) / (t[lo + 1] - t[lo]);
      if (i >= hi - 1) return (x[hi - 1] - x[hi - 2]) / (t[hi - 1] - t[hi - 2]);
      return (x[i + 1] - x[i - 1]) / (t[i + 1] - t[i - 1]);
    };
    const double m0 = slope(i0) * h, m1 = slope(i1) * h;
    const double s2 = s * s, s3 = s2 * s;
    return (2 * s3 - 3 * s2 + 1) * x[i0] + (s3 - 2 * s2 + s) * m0 + (-2 * s3 + 3 * s2) * x[i1] +
           (s3 - s2) * m1;
  }
};

}  // namespace

namespace {

// Segment boundaries of the channel input: 0, the segment starts inside
// (0, n), n.
std::vector<int> SegmentBounds(const ChannelInput& in) {
  std::vector<int> bounds;
  bounds.push_back(0);
  if (in.segment_starts) {
    for (int s : *in.segment_starts)
      if (s > bounds.back() && s < in.n) bounds.push_back(s);
  }
  bounds.push_back(in.n);
  return bounds;
}

// Pure delay of out[lo, hi) (cubic interpolation; tmp is scratch).
void ApplyDelay(double delay, const double* t, int lo, int hi, std::vector<double>& out,
                std::vector<double>& tmp) {
  tmp.assign(out.begin() + lo, out.begin() + hi);
  Interp ip{t + lo, tmp.data(), 0, hi - lo, 0};
  for (int i = lo; i < hi; ++i) out[i] = ip(t[i] - delay);
}

// First-order lag of out[lo, hi): the exact solution of tau y' = u - y for u
// linear between samples, starting at rest on the first sample.
void ApplyLag(double lag, const double* t, int lo, int hi, std::vector<double>& out) {
  double y = out[lo];
  double uprev = out[lo];
  for (int i = lo + 1; i < hi; ++i) {
    const double h = t[i] - t[i - 1];
    const double u = out[i];
    const double e = std::exp(-h / lag);
    const double slope = (u - uprev) / h;
    y = u - lag * slope + e * (y - uprev + lag * slope);
    uprev = u;
    out[i] = y;
  }
}

// Play operator of the given loop width on out[lo, hi), starting released.
void ApplyPlay(double width, int lo, int hi, std::vector<double>& out) {
  const double r = 0.5 * width;
  double state = 0;  // starts released
  for (int i = lo; i < hi; ++i) {
    const double u = out[i];
    state = std::max(u - r, std::min(u + r, state));
    out[i] = state;
  }
}

// Prandtl-Ishlinskii hysteresis on out[lo, hi): the weighted sum of play
// operators (weights normalised by their sum), every operator starting
// released (0). Nothing when the weights sum to 0.
void ApplyPrandtlIshlinskii(const EffectParams& p, int lo, int hi, std::vector<double>& out) {
  const size_t K = p.pi_thresholds.size();
  double wsum = 0;
  for (double w : p.pi_weights) wsum += w;
  if (!(wsum > 0)) return;
  std::vector<double> state(K, 0.0);
  for (int i = lo; i < hi; ++i) {
    const double u = out[i];
    double y = 0;
    for (size_t k = 0; k < K; ++k) {
      const double r = p.pi_thresholds[k];
      state[k] = std::max(u - r, std::min(u + r, state[k]));
      y += p.pi_weights[k] * state[k];
    }
    out[i] = y / wsum;
  }
}

// The static effects and drift, sample by sample: power law, curvature,
// threshold, saturation, drift.
void ApplyStaticEffects(const EffectParams& p, const ChannelInput& in, std::vector<double>& out) {
  const bool has_curv = p.curvature != 0;
  const double cscale = has_curv ? p.curvature / p.full_scale : 0;
  const bool has_pow = p.power_exponent > 0 && p.power_exponent != 1;
  for (int i = 0; i < in.n; ++i) {
    double u = out[i];
    if (has_pow && u != 0)
      u = (u < 0 ? -p.full_scale : p.full_scale) *
          std::pow(std::abs(u) / p.full_scale, p.power_exponent);
    if (has_curv) u += cscale * u * std::abs(u);
    if (p.threshold > 0) u = (u < p.threshold) ? 0.0 : u - p.threshold_shift * p.threshold;
    if (p.saturation > 0 && u > p.saturation) u = p.saturation;
    if (p.drift != 0) u += p.drift * (in.t[i] - in.t0);
    out[i] = u;
  }
}

}  // namespace

void ApplyChannel(const EffectParams& p, const ChannelInput& in, std::vector<double>* out_ptr) {
  std::vector<double>& out = *out_ptr;
  const int n = in.n;
  out.resize(n);
  for (int i = 0; i < n; ++i)
    out[i] = in.force[i] + (in.shear && p.crosstalk != 0 ? p.crosstalk * in.shear[i] : 0.0);
  const bool has_pi = !p.pi_thresholds.empty() && p.pi_thresholds.size() == p.pi_weights.size();
  const bool dynamic = p.delay != 0 || p.lag > 0 || p.hysteresis_width > 0 || has_pi;
  if (dynamic) {
    // The dynamic effects restart in every segment (trial).
    const std::vector<int> bounds = SegmentBounds(in);
    std::vector<double> tmp;
    for (size_t s = 0; s + 1 < bounds.size(); ++s) {
      const int lo = bounds[s], hi = bounds[s + 1];
      if (hi - lo < 2) continue;
      if (p.delay != 0) ApplyDelay(p.delay, in.t, lo, hi, out, tmp);
      if (p.lag > 0) ApplyLag(p.lag, in.t, lo, hi, out);
      if (p.hysteresis_width > 0)
        ApplyPlay(p.hysteresis_width, lo, hi, out);
      else if (has_pi)
        ApplyPrandtlIshlinskii(p, lo, hi, out);
    }
  }
  ApplyStaticEffects(p, in, out);
}

std::vector<double> PredictReading(const SensorModel& model, const std::vector<double>& t,
                                   const std::vector<double>& reference,
                                   const std::vector<double>& shear,
                                   const std::vector<int>& segment_starts) {
  ChannelInput in;
  in.t = t.data();
  in.force = reference.data();
  in.shear = shear.size() == reference.size() ? shear.data() : nullptr;
  in.n = static_cast<int>(reference.size());
  in.segment_starts = &segment_starts;
  in.t0 = t.empty() ? 0 : t.front();
  std::vector<double> out;
  ApplyChannel(model.effects, in, &out);
  for (double& v : out) v = model.gain * v + model.offset;
  return out;
}

double CorrectReading(const SensorModel& m, double reading, double t_since_start, double shear) {
  const EffectParams& p = m.effects;
  double u = (reading - m.offset) / m.gain;
  u -= p.drift * t_since_start;
  if (p.saturation > 0 && u >= p.saturation) u = p.saturation;
  if (p.threshold > 0 && u > 0) u += p.threshold_shift * p.threshold;
  if (p.curvature != 0) {
    // Solve v + c v|v| = u (monotone where 1 + 2c|v| > 0).
    const double c = p.curvature / p.full_scale;
    double v = u;
    for (int it = 0; it < 30; ++it) {
      const double f = v + c * v * std::abs(v) - u;
      const double d = 1 + 2 * c * std::abs(v);
      if (d <= 1e-6) break;
      const double step = f / d;
      v -= step;
      if (std::abs(step) < 1e-12) break;
    }
    u = v;
  }
  if (p.power_exponent > 0 && p.power_exponent != 1 && u != 0)
    u = (u < 0 ? -p.full_scale : p.full_scale) *
        std::pow(std::abs(u) / p.full_scale, 1.0 / p.power_exponent);
  u -= p.crosstalk * shear;
  return u;
}

}  // namespace tactforce::sim
