// The streaming taxel array (taxel_array.h): the ranges (validation, JSON),
// the per-taxel draws, where a contact's force lands on the taxels, and the
// per-taxel activation / hysteresis / saturation / error / noise chain.
#include "tactforce/sim/taxel_array.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include <Eigen/Geometry>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/io/json.h"
#include "tactforce/io/suggest.h"
#include "tactforce/io/text_file.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::sim {
namespace {

constexpr char kFormat[] = "tactforce.taxel_ranges.v1";
constexpr double kReleaseFloor =
    0.01;  // N: an active taxel whose hysteresis state relaxes below this deactivates

struct RangeField {
  const char* name;
  double TaxelRanges::*member;
};
const std::vector<RangeField>& RangeFields() {
  static const std::vector<RangeField> fields = {
      {"threshold_min", &TaxelRanges::threshold_min},
      {"threshold_max", &TaxelRanges::threshold_max},
      {"hysteresis_max", &TaxelRanges::hysteresis_max},
      {"hysteresis_decay", &TaxelRanges::hysteresis_decay},
      {"force_error_min", &TaxelRanges::force_error_min},
      {"force_error_max", &TaxelRanges::force_error_max},
      {"noise_min", &TaxelRanges::noise_min},
      {"noise_max", &TaxelRanges::noise_max},
      {"saturation", &TaxelRanges::saturation},
      {"patch_radius_coeff", &TaxelRanges::patch_radius_coeff},
      {"patch_radius_max", &TaxelRanges::patch_radius_max},
      {"taxel_radius", &TaxelRanges::taxel_radius},
  };
  return fields;
}

}  // namespace

absl::Status ValidateTaxelRanges(const TaxelRanges& r, const std::string& prefix) {
  for (const RangeField& f : RangeFields()) {
    const double v = r.*f.member;
    if (!(v >= 0 && std::isfinite(v)))
      return absl::InvalidArgumentError(
          absl::StrFormat("%s%s: must be >= 0 and finite, got %g", prefix, f.name, v));
  }
  auto ordered = [&](const char* lo_name, double lo, const char* hi_name,
                     double hi) -> absl::Status {
    if (hi < lo)
      return absl::InvalidArgumentError(
          absl::StrFormat("%s%s: must be >= %s (%g), got %g", prefix, hi_name, lo_name, lo, hi));
    return absl::OkStatus();
  };
  TF_RETURN_IF_ERROR(ordered("threshold_min", r.threshold_min, "threshold_max", r.threshold_max));
  TF_RETURN_IF_ERROR(
      ordered("force_error_min", r.force_error_min, "force_error_max", r.force_error_max));
  TF_RETURN_IF_ERROR(ordered("noise_min", r.noise_min, "noise_max", r.noise_max));
  if (!(r.saturation > r.threshold_max))
    return absl::InvalidArgumentError(
        absl::StrFormat("%ssaturation: must exceed threshold_max (%g N), got %g", prefix,
                        r.threshold_max, r.saturation));
  if (!(r.patch_radius_coeff > 0))
    return absl::InvalidArgumentError(
        absl::StrFormat("%spatch_radius_coeff: must be > 0, got %g", prefix, r.patch_radius_coeff));
  if (!(r.taxel_radius > 0))
    return absl::InvalidArgumentError(
        absl::StrFormat("%staxel_radius: must be > 0, got %g", prefix, r.taxel_radius));
  return absl::OkStatus();
}

absl::StatusOr<TaxelRanges> TaxelRangesFromJson(const std::string& text,
                                                const std::string& source) {
  TF_ASSIGN_OR_RETURN(auto doc, io::ParseJson(text, source));
  if (!doc.is_object())
    return absl::InvalidArgumentError(absl::StrCat(source, ": taxel ranges must be a JSON object"));
  TaxelRanges r;
  std::vector<std::string> keys = {"format"};
  for (const RangeField& f : RangeFields()) keys.push_back(f.name);
  for (const auto& [key, v] : doc.members()) {
    const std::string where = absl::StrCat(source, ":", v.line(), ": field '", key, "'");
    if (key == "format") {
      if (!v.is_string() || v.string() != kFormat)
        return absl::InvalidArgumentError(absl::StrCat(where, ": expected \"", kFormat, "\""));
      continue;
    }
    auto it = std::find_if(RangeFields().begin(), RangeFields().end(),
                           [&](const RangeField& f) { return key == f.name; });
    if (it == RangeFields().end())
      return absl::InvalidArgumentError(
          absl::StrCat(where, ": unknown field", io::DidYouMean(key, keys)));
    if (!v.is_number())
      return absl::InvalidArgumentError(absl::StrCat(where, ": expected a number"));
    r.*(it->member) = v.number();
    // Range errors name the line of the offending field.
    if (absl::Status s = ValidateTaxelRanges(r); !s.ok() && absl::StartsWith(s.message(), it->name))
      return absl::InvalidArgumentError(
          absl::StrCat(source, ":", v.line(), ": field ", s.message()));
  }
  if (absl::Status s = ValidateTaxelRanges(r); !s.ok())
    return absl::InvalidArgumentError(absl::StrCat(source, ": field ", s.message()));
  return r;
}

absl::StatusOr<TaxelRanges> LoadTaxelRanges(const std::string& path) {
  TF_ASSIGN_OR_RETURN(std::string text, io::ReadTextFile(path));
  return TaxelRangesFromJson(text, io::SourceName(path));
}

std::string TaxelRangesToJson(const TaxelRanges& r) {
  io::JsonWriter w;
  w.BeginObject();
  w.Field("format", kFormat);
  for (const RangeField& f : RangeFields()) w.Field(f.name, r.*f.member);
  w.EndObject();
  return w.str();
}

namespace {

constexpr int kPatchRays = 64;  // rays of the patch integral (the radial part is exact)

// The surface normal at `contact`, blended smoothly from the taxels near it
// (weights (1 - d / reach)^2), or the nearest taxel's if none is that close.
Eigen::Vector3d SurfaceNormal(const std::vector<Taxel>& taxels, const Eigen::Vector3d& contact,
                              double reach) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  size_t nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < taxels.size(); ++i) {
    const double d = (taxels[i].position - contact).norm();
    if (d < best) best = d, nearest = i;
    if (d < reach) n += std::pow(1 - d / reach, 2) * taxels[i].normal;
  }
  return n.norm() > 1e-12 ? n.normalized() : taxels[nearest].normal;
}

// Hertz pressure p(r) ~ sqrt(1 - r^2 / a^2): the fraction of the patch's force
// within radius r of its centre (r <= a).
double HertzFraction(double r, double a) {
  return 1 - std::pow(std::max(0.0, 1 - r * r / (a * a)), 1.5);
}

// Adds to `share` each taxel's fraction of the pressure along one ray c + r u
// (r in [0, a]) of the patch: every point belongs to its nearest taxel, and
// along a straight ray the nearest changes where a squared-distance difference
// (linear in r) crosses zero, so the radial integral is exact.
void IntegrateRay(const std::vector<Taxel>& taxels, const std::vector<size_t>& candidates,
                  const Eigen::Vector3d& c, const Eigen::Vector3d& u, double a, double ray_weight,
                  std::vector<double>* share) {
  size_t cur = candidates[0];
  for (size_t j : candidates)
    if ((taxels[j].position - c).squaredNorm() < (taxels[cur].position - c).squaredNorm()) cur = j;
  double r = 0;
  while (r < a) {
    // |c + r u - p_j|^2 - |c + r u - p_cur|^2 = A_j + 2 r B_j.
    double next = a;
    size_t next_taxel = cur;
    for (size_t j : candidates) {
      if (j == cur) continue;
      const double A =
          (taxels[j].position - c).squaredNorm() - (taxels[cur].position - c).squaredNorm();
      const double B = u.dot(taxels[cur].position - taxels[j].position);
      if (B >= 0) continue;  // taxel j never gets nearer along this ray
      const double cross = -A / (2 * B);
      if (cross > r + 1e-12 && cross < next) next = cross, next_taxel = j;
    }
    (*share)[cur] += ray_weight * (HertzFraction(next, a) - HertzFraction(r, a));
    r = next;
    cur = next_taxel;
  }
}

}  // namespace

Taxel ProjectOntoFingertip(const FingertipGeometry& g, const Eigen::Vector3d& p) {
  const Eigen::Vector3d centre(0, 0, g.body_length);
  Eigen::Vector3d n =
      p.z() >= g.body_length ? Eigen::Vector3d(p - centre) : Eigen::Vector3d(p.x(), p.y(), 0);
  if (n.norm() < 1e-12) n = Eigen::Vector3d::UnitZ();  // the centre (or axis): the apex
  n.normalize();
  if (p.z() >= g.body_length || n.z() > 0) return {centre + g.radius * n, n};
  return {Eigen::Vector3d(g.radius * n.x(), g.radius * n.y(), p.z()), n};
}

double DomeResolutionDeg(const std::vector<Taxel>& taxels, const FingertipGeometry& g) {
  const Eigen::Vector3d centre(0, 0, g.body_length);
  std::vector<Eigen::Vector3d> dirs;
  for (const Taxel& t : taxels)
    if ((t.position - centre).norm() > 1e-12) dirs.push_back((t.position - centre).normalized());
  if (dirs.empty()) return 180;
  // The smallest cosine to the nearest taxel over a 0.5 deg grid of the dome.
  double min_best = 1;
  for (int ip = 0; ip <= 180; ++ip) {
    const double polar = ip * std::numbers::pi / 360;
    const int n_az = std::max(1, static_cast<int>(std::ceil(720 * std::sin(polar))));
    for (int ia = 0; ia < n_az; ++ia) {
      const double az = 2 * std::numbers::pi * ia / n_az;
      const Eigen::Vector3d u(std::sin(polar) * std::cos(az), std::sin(polar) * std::sin(az),
                              std::cos(polar));
      double best = -1;
      for (const Eigen::Vector3d& d : dirs) best = std::max(best, u.dot(d));
      min_best = std::min(min_best, best);
    }
  }
  return std::acos(std::clamp(min_best, -1.0, 1.0)) * 180 / std::numbers::pi;
}

TaxelLoads ComputeTaxelLoads(const std::vector<Taxel>& taxels, const TaxelRanges& r,
                             const Eigen::Vector3d& contact, const Eigen::Vector3d& force) {
  const size_t n = taxels.size();
  TaxelLoads out;
  out.load.assign(n, 0.0);
  out.coverage.assign(n, 0.0);
  out.misalignment.assign(n, 1.0);
  const double f = force.norm();
  if (!(f > 0) || !contact.allFinite() || n == 0) return out;
  out.patch_radius = std::min(r.patch_radius_max, r.patch_radius_coeff * std::cbrt(f));
  const double a = out.patch_radius, reach = a + r.taxel_radius;
  // Taxels that can own part of the patch: the nearest one's cell reaches at
  // most its distance + 2a from the contact.
  double nearest = std::numeric_limits<double>::infinity();
  for (const Taxel& t : taxels) nearest = std::min(nearest, (t.position - contact).norm());
  std::vector<size_t> candidates;
  for (size_t i = 0; i < n; ++i) {
    const double d = (taxels[i].position - contact).norm();
    if (d <= nearest + 2 * a) candidates.push_back(i);
    out.coverage[i] = std::clamp((reach - d) / (2 * r.taxel_radius), 0.0, 1.0);
  }
  // The patch's plane from a neighbourhood that does not grow with the force:
  // a plane that tilted as the patch grew moved pressure between cells, so a
  // taxel's load could fall while the force rose.
  const Eigen::Vector3d normal =
      SurfaceNormal(taxels, contact, r.patch_radius_max + r.taxel_radius);
  const Eigen::Vector3d e1 = normal.unitOrthogonal(), e2 = normal.cross(e1);
  std::vector<double> share(n, 0.0);
  for (int k = 0; k < kPatchRays; ++k) {
    const double th = 2 * std::numbers::pi * (k + 0.5) / kPatchRays;
    IntegrateRay(taxels, candidates, contact, std::cos(th) * e1 + std::sin(th) * e2, a,
                 1.0 / kPatchRays, &share);
  }
  for (size_t i = 0; i < n; ++i) {
    const double cosine = std::max(0.0, -force.dot(taxels[i].normal) / f);
    out.misalignment[i] = 1 - cosine;
    out.load[i] = share[i] * f * cosine;
  }
  return out;
}

TaxelArray::TaxelArray(const TaxelRanges& r, uint64_t seed, const FingertipGeometry& g)
    : ranges_(r), taxels_(DefaultFingertip(g)), noise_rng_(seed ^ 0x5deece66dULL) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  auto draw = [&](double lo, double hi) { return lo + (hi - lo) * u01(rng); };
  for (size_t i = 0; i < taxels_.size(); ++i) {
    TaxelParams p;
    p.threshold = draw(r.threshold_min, r.threshold_max);
    p.hysteresis = draw(0.0, r.hysteresis_max);
    const double sign = u01(rng) < 0.5 ? -1.0 : 1.0;
    p.force_error = sign * draw(r.force_error_min, r.force_error_max);
    p.noise = draw(r.noise_min, r.noise_max);
    params_.push_back(p);
  }
  active_.assign(taxels_.size(), 0);
  play_.assign(taxels_.size(), 0.0);
  out_.reading.assign(taxels_.size(), 0.0);
}

absl::StatusOr<TaxelArray> TaxelArray::Create(const TaxelRanges& ranges, uint64_t seed,
                                              const FingertipGeometry& geometry) {
  TF_RETURN_IF_ERROR(ValidateTaxelRanges(ranges));
  if (!(geometry.radius > 0) || !(geometry.body_length >= 0))
    return absl::InvalidArgumentError("geometry: radius must be > 0 and body_length >= 0");
  return TaxelArray(ranges, seed, geometry);
}

const TaxelArrayReading& TaxelArray::Step(double t, const Eigen::Vector3d& contact,
                                          const Eigen::Vector3d& force) {
  const double dt = started_ ? std::max(0.0, t - prev_t_) : 0.0;
  started_ = true;
  prev_t_ = t;
  const double relax =
      ranges_.hysteresis_decay > 0 ? 1 - std::exp(-dt / ranges_.hysteresis_decay) : 0.0;
  const TaxelLoads loads = ComputeTaxelLoads(taxels_, ranges_, contact, force);
  out_.load = loads.load;
  out_.true_force = force.allFinite() ? force.norm() : 0.0;
  out_.active = 0;
  for (size_t i = 0; i < taxels_.size(); ++i) {
    const TaxelParams& p = params_[i];
    const double u = loads.load[i];
    double& y = play_[i];
    if (!active_[i] && u >= p.threshold) active_[i] = 1, y = u;  // the activation jump
    if (!active_[i]) {
      out_.reading[i] = 0;
      continue;
    }
    y = std::clamp(y, u - p.hysteresis, u + p.hysteresis);
    y += (u - y) * relax;
    if (u <= 0 && y < kReleaseFloor) {
      active_[i] = 0;
      out_.reading[i] = 0;
      continue;
    }
    double v = std::min(y, ranges_.saturation);
    // A piezo taxel reads a non-negative calibrated force: the error cannot
    // take a loaded taxel below zero.
    if (u > 0)
      v = std::max(0.0, v + p.force_error * std::max(1 - loads.coverage[i], loads.misalignment[i]));
    out_.reading[i] = v + p.noise * gauss_(noise_rng_);
    ++out_.active;
  }
  out_.fingertip = AggregateFingertip(taxels_, out_.reading);
  return out_;
}

}  // namespace tactforce::sim
