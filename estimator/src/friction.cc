// Friction from slip (friction.h, Sundaralingam & Hermans): per trial the
// slip onset from the contact point's motion, the force just before it and
// mu = tan(acos(f_hat . n)); robust statistics over trials; the trial CSV;
// and simulated trials for tests and benchmarks.
#include "tactforce/estimator/friction.h"

#include <algorithm>
#include <cmath>
#include <random>

#include <Eigen/Dense>

#include "absl/strings/str_cat.h"
#include "tactforce/planner/validation.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::estimator {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// Linear-interpolated quantile of sorted data.
double Quantile(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return 0.0;
  const double pos = q * (sorted.size() - 1);
  const size_t lo = static_cast<size_t>(std::floor(pos));
  const size_t hi = std::min(lo + 1, sorted.size() - 1);
  return sorted[lo] + (pos - lo) * (sorted[hi] - sorted[lo]);
}

absl::Status ValidateTrial(const FrictionTrial& trial, int index, int min_samples) {
  const std::string path = absl::StrCat("trials[", index, "]");
  if (static_cast<int>(trial.samples.size()) < min_samples) {
    return absl::InvalidArgumentError(absl::StrCat(path, ".samples: ", trial.samples.size(),
                                                   " samples, need at least ", min_samples));
  }
  for (size_t k = 0; k < trial.samples.size(); ++k) {
    const FrictionSample& s = trial.samples[k];
    const std::string sp = absl::StrCat(path, ".samples[", k, "]");
    if (!std::isfinite(s.t)) return absl::InvalidArgumentError(sp + ".t: not a finite number");
    if (!s.force.allFinite()) return absl::InvalidArgumentError(sp + ".force: not finite");
    if (!s.contact_point.allFinite())
      return absl::InvalidArgumentError(sp + ".contact_point: not finite");
    if (k > 0 && !(s.t > trial.samples[k - 1].t))
      return absl::InvalidArgumentError(sp + ".t: not increasing");
    // The pre-slip line fit is over time: steps below the resolution are noise.
    TF_RETURN_IF_ERROR(
        planner::CheckTime(sp + ".t", s.t, k > 0 ? &trial.samples[k - 1].t : nullptr));
    TF_RETURN_IF_ERROR(planner::CheckMagnitude(sp + ".force", s.force, planner::kMaxForce, "N"));
    TF_RETURN_IF_ERROR(
        planner::CheckMagnitude(sp + ".contact_point", s.contact_point, planner::kMaxLength, "m"));
  }
  Vec3 unit = trial.normal.value_or(Vec3::UnitZ());
  if (trial.normal && !planner::NormalizeDirection(&unit))
    return absl::InvalidArgumentError(
        path + (unit.allFinite() ? ".normal: zero length" : ".normal: not finite"));
  return absl::OkStatus();
}

// Force just before the onset: window mean, or line fits evaluated at the
// last static sample.
Vec3 PreSlipForceAt(const FrictionTrial& trial, int last_static, double t_onset,
                    const FrictionOptions& o) {
  if (o.pre_slip == PreSlipForce::kWindowAverage) {
    const int first = std::max(0, last_static - o.window + 1);
    Vec3 sum = Vec3::Zero();
    for (int k = first; k <= last_static; ++k) sum += trial.samples[k].force;
    return sum / (last_static - first + 1);
  }
  const int first = std::max(0, last_static - o.fit_window + 1);
  const int m = last_static - first + 1;
  if (m < 3) return trial.samples[last_static].force;
  Eigen::MatrixXd a(m, 2);
  Eigen::MatrixXd y(m, 3);
  const double t_end = t_onset;  // the fit is evaluated at the onset
  for (int k = 0; k < m; ++k) {
    const FrictionSample& s = trial.samples[first + k];
    a(k, 0) = 1.0;
    a(k, 1) = s.t - t_end;
    y.row(k) = s.force.transpose();
  }
  const Eigen::MatrixXd coef = a.colPivHouseholderQr().solve(y);
  return coef.row(0).transpose();  // value at the onset
}

// The estimate's own error model: the standard error of |f_t| / f_n over
// the samples the pre-slip force is taken from (0 for a single sample).
double RatioStandardError(const FrictionTrial& trial, const Vec3& n, int last_static,
                          const FrictionOptions& o) {
  const int span = o.pre_slip == PreSlipForce::kWindowAverage ? o.window : o.fit_window;
  const int first = std::max(0, last_static - span + 1);
  const int m = last_static - first + 1;
  if (m < 2) return 0.0;
  double sum = 0.0, sum2 = 0.0;
  for (int k = first; k <= last_static; ++k) {
    const Vec3& f = trial.samples[k].force;
    const double fn = f.dot(n);
    const double ratio = fn > 0 ? (f - fn * n).norm() / fn : 0.0;
    sum += ratio;
    sum2 += ratio * ratio;
  }
  const double variance = std::max(0.0, (sum2 - sum * sum / m) / (m - 1));
  return std::sqrt(variance / m);
}

// The first sample flagged as slipping, else the first whose tangential
// travel from the first sample exceeds `slip_distance`; -1 when neither.
int DetectSlip(const std::vector<FrictionSample>& s, const Eigen::Matrix3d& tangent_projector,
               double slip_distance) {
  for (size_t k = 0; k < s.size(); ++k) {
    if (s[k].slip.has_value() && *s[k].slip) return static_cast<int>(k);
  }
  for (size_t k = 1; k < s.size(); ++k) {
    if ((tangent_projector * (s[k].contact_point - s[0].contact_point)).norm() > slip_distance)
      return static_cast<int>(k);
  }
  return -1;
}

TrialFriction EstimateTrial(const FrictionTrial& trial, const Vec3& n, const FrictionOptions& o) {
  TrialFriction out;
  out.name = trial.name;
  out.normal = n;
  const auto& s = trial.samples;
  const int count = static_cast<int>(s.size());
  const Eigen::Matrix3d tangent_projector = Eigen::Matrix3d::Identity() - n * n.transpose();

  const int detect = DetectSlip(s, tangent_projector, o.slip_distance);
  auto ratio = [&](const Vec3& f) {
    const double fn = f.dot(n);
    return std::pair<double, double>{fn, (f - fn * n).norm()};
  };
  if (detect < 0) {  // no slip: a lower bound
    double best = 0.0;
    for (const auto& smp : s) {
      const auto [fn, ft] = ratio(smp.force);
      if (fn >= o.min_normal_force) best = std::max(best, ft / fn);
    }
    out.valid = true;
    out.lower_bound = true;
    out.mu = best;
    out.message = absl::StrCat("no slip detected: mu >= ", best);
    return out;
  }
  out.slipped = true;
  out.detection_index = detect;

  // Back-track to where the motion began: the tangential displacement from
  // the resting position rises above its noise level (median + k MAD over
  // the quiet first half before detection) and stays above it until detection.
  const int quiet_end = std::max(2, detect / 2);
  Vec3 rest = Vec3::Zero();
  for (int k = 0; k < quiet_end; ++k) rest += s[k].contact_point;
  rest /= quiet_end;
  std::vector<double> travel(count);
  for (int k = 0; k < count; ++k)
    travel[k] = (tangent_projector * (s[k].contact_point - rest)).norm();
  std::vector<double> quiet(travel.begin(), travel.begin() + quiet_end);
  const double med = Median(quiet);
  std::vector<double> dev;
  for (double v : quiet) dev.push_back(std::abs(v - med));
  const double threshold =
      std::max(med + o.noise_k * 1.4826 * Median(dev), o.min_onset_fraction * o.slip_distance);
  int onset = detect;
  while (onset - 1 >= 1 && travel[onset - 1] > threshold) --onset;
  // `onset` is now the first displaced sample, so the motion began from the
  // sample before it; the pre-slip window ends one sample before that, which
  // also guards against a first moving sample still inside the noise.
  --onset;
  // Slip flagged at the first sample: onset -1 (the csv fuzzer saw s[-1] read).
  out.slip_index = std::max(onset, 0);
  out.slip_time = s[out.slip_index].t;
  const int last_static = onset - 1;
  if (last_static < 0) {
    out.message = "slip at the first sample: no pre-slip force";
    return out;
  }
  const Vec3 f = PreSlipForceAt(trial, last_static, s[onset].t, o);
  const auto [fn, ft] = ratio(f);
  if (fn < o.min_normal_force) {
    out.message = absl::StrCat("normal force before slip ", fn, " N is below the minimum ",
                               o.min_normal_force, " N");
    return out;
  }
  out.valid = true;
  out.mu = ft / fn;
  out.mu_sigma = RatioStandardError(trial, n, last_static, o);
  out.force_angle = std::acos(std::clamp(f.normalized().dot(n), -1.0, 1.0));
  return out;
}

// Each option by its name (the FrictionRequest field), with its value.
absl::Status ValidateOptions(const FrictionOptions& o) {
  auto bad = [](const char* field, const char* rule, double value) {
    return absl::InvalidArgumentError(
        absl::StrCat(field, ": must be ", rule, " (got ", value, ")"));
  };
  if (!(o.slip_distance > 0) || !std::isfinite(o.slip_distance))
    return bad("slip_distance", "finite and > 0 m", o.slip_distance);
  TF_RETURN_IF_ERROR(
      planner::CheckMagnitude("slip_distance", o.slip_distance, planner::kMaxLength, "m"));
  if (o.window < 1) return bad("window", ">= 1 sample", o.window);
  if (o.fit_window < 3) return bad("fit_window", ">= 3 samples", o.fit_window);
  if (!(o.min_normal_force >= 0) || !std::isfinite(o.min_normal_force))
    return bad("min_normal_force", "finite and >= 0 N", o.min_normal_force);
  TF_RETURN_IF_ERROR(
      planner::CheckMagnitude("min_normal_force", o.min_normal_force, planner::kMaxForce, "N"));
  if (!(o.noise_k > 0) || !std::isfinite(o.noise_k))
    return bad("noise_k", "finite and > 0", o.noise_k);
  if (!(o.min_onset_fraction >= 0 && o.min_onset_fraction < 1))
    return bad("min_onset_fraction", "in [0, 1)", o.min_onset_fraction);
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<FrictionEstimate> EstimateFriction(const std::vector<FrictionTrial>& trials,
                                                  const FrictionOptions& o) {
  if (trials.empty()) return absl::InvalidArgumentError("trials: empty");
  TF_RETURN_IF_ERROR(ValidateOptions(o));
  if (o.mesh) {
    TF_RETURN_IF_ERROR(io::ValidateMesh(*o.mesh));
  }
  FrictionEstimate out;
  for (int i = 0; i < static_cast<int>(trials.size()); ++i) {
    if (o.interrupt && o.interrupt()) {
      return absl::CancelledError(
          absl::StrCat("interrupted after ", i, " of ", trials.size(), " trials"));
    }
    const FrictionTrial& trial = trials[i];
    TF_RETURN_IF_ERROR(ValidateTrial(trial, i, 3));
    Vec3 n;
    int triangle = -1;
    if (trial.normal) {
      n = *trial.normal;
      planner::NormalizeDirection(&n);  // without overflow; ValidateTrial accepted it
    } else if (o.mesh) {
      const io::NearestTriangle near =
          io::FindNearestTriangle(*o.mesh, trial.samples.front().contact_point);
      n = near.inward_normal;
      triangle = near.triangle;
    } else {
      return absl::InvalidArgumentError(absl::StrCat("trials[", i, "]: no normal and no mesh"));
    }
    TrialFriction r = EstimateTrial(trial, n, o);
    r.mesh_triangle = triangle;
    out.trials.push_back(std::move(r));
  }
  std::vector<double> mus;
  for (const auto& t : out.trials) {
    if (t.valid && t.slipped) mus.push_back(t.mu);
  }
  out.count = static_cast<int>(mus.size());
  if (!mus.empty()) {
    std::sort(mus.begin(), mus.end());
    out.median = Median(mus);
    double sum = 0;
    for (double m : mus) sum += m;
    out.mean = sum / mus.size();
    out.iqr = Quantile(mus, 0.75) - Quantile(mus, 0.25);
    if (mus.size() >= 2) {
      double squares = 0;
      for (double m : mus) squares += (m - out.mean) * (m - out.mean);
      out.mu_sigma = std::sqrt(squares / (mus.size() - 1));
    } else {
      for (const auto& t : out.trials) {
        if (t.valid && t.slipped) out.mu_sigma = t.mu_sigma;
      }
    }
  }
  return out;
}

absl::StatusOr<FrictionTrial> FrictionTrialFromCsv(const io::CsvTable& table) {
  TF_RETURN_IF_ERROR(table.Require({"t", "fx", "fy", "fz", "px", "py", "pz"}));
  FrictionTrial trial;
  trial.name = table.source;
  const int slip = table.ColumnIndex("slip");
  const int c[7] = {table.ColumnIndex("t"),  table.ColumnIndex("fx"), table.ColumnIndex("fy"),
                    table.ColumnIndex("fz"), table.ColumnIndex("px"), table.ColumnIndex("py"),
                    table.ColumnIndex("pz")};
  for (size_t r = 0; r < table.rows.size(); ++r) {
    const auto& row = table.rows[r];
    FrictionSample s;
    s.t = row[c[0]];
    s.force = Vec3(row[c[1]], row[c[2]], row[c[3]]);
    s.contact_point = Vec3(row[c[4]], row[c[5]], row[c[6]]);
    if (slip >= 0) {
      if (row[slip] != 0.0 && row[slip] != 1.0)
        return absl::InvalidArgumentError(absl::StrCat(table.source, ":", table.line_numbers[r],
                                                       ": column 'slip': must be 0 or 1"));
      s.slip = row[slip] != 0.0;
    }
    if (r > 0 && !(s.t > trial.samples.back().t))
      return absl::InvalidArgumentError(
          absl::StrCat(table.source, ":", table.line_numbers[r], ": column 't': not increasing"));
    trial.samples.push_back(s);
  }
  return trial;
}

SimulatedFriction SimulateFriction(const FrictionSimOptions& o) {
  SimulatedFriction out;
  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> gauss;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  // A probe pressing down on the top face of an object: n points into it.
  out.normal = Vec3(0, 0, -1);
  for (int trial = 0; trial < o.trials; ++trial) {
    const double heading = 2 * M_PI * unit(rng);
    const Vec3 tangent(std::cos(heading), std::sin(heading), 0);
    const Vec3 start(0.01 * (unit(rng) - 0.5), 0.01 * (unit(rng) - 0.5), 0.02);
    const double ft = o.tangential_force;
    const double fn_slip = ft / o.mu;
    const double fn0 = fn_slip * (1.3 + 0.2 * unit(rng));
    const double t_slip = (fn0 - fn_slip) / o.ramp;
    const double t_end = t_slip + o.duration_after_slip;
    const double dt = 1.0 / o.rate;
    const double phase = dt * unit(rng);  // slip falls anywhere between samples
    FrictionTrial tr;
    tr.name = absl::StrCat("trial", trial);
    tr.normal = out.normal;
    for (double t = phase; t <= t_end; t += dt) {
      const double fn = std::max(0.0, fn0 - o.ramp * t);
      FrictionSample s;
      s.t = t;
      double travel = 0.0, f_t = ft;
      if (t > t_slip) {
        const double tau = t - t_slip;
        f_t = std::min(ft, 0.8 * o.mu * fn);  // kinetic
        const double accel = std::max(1e-3, (ft - f_t) / o.probe_mass);
        const double t_reach = o.slide_speed / accel;
        travel = tau < t_reach ? 0.5 * accel * tau * tau
                               : 0.5 * accel * t_reach * t_reach + o.slide_speed * (tau - t_reach);
      }
      s.force = fn * out.normal + f_t * tangent +
                o.force_noise * Vec3(gauss(rng), gauss(rng), gauss(rng));
      s.contact_point =
          start + travel * tangent + o.position_noise * Vec3(gauss(rng), gauss(rng), gauss(rng));
      if (o.write_slip_flags) s.slip = t > t_slip;
      tr.samples.push_back(s);
    }
    out.trials.push_back(std::move(tr));
    out.true_slip_time.push_back(t_slip);
  }
  return out;
}

}  // namespace tactforce::estimator
