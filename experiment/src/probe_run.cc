// The probe experiment's trials and summary (probe.h): per trial the set-up,
// the simulation, EstimateFriction on the sensed samples with the box's mesh
// for the normal, and the validity rule; per surface the slope method and the
// plate probe (RunSlopeAndProbe) as references; medians over valid trials.
#include <algorithm>
#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "probe_internal.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

uint64_t Mix(uint64_t x) {  // SplitMix64
  x += 0x9e3779b97f4a7c15ULL;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ULL;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebULL;
  return x ^ (x >> 31);
}

// Seed of (seed, surface name, trial): independent of what else runs.
uint64_t TrialSeed(uint64_t seed, const std::string& surface, int trial) {
  uint64_t h = 1469598103934665603ULL;  // FNV-1a of the name
  for (unsigned char ch : surface) h = (h ^ ch) * 1099511628211ULL;
  return Mix(Mix(seed) ^ Mix(h) ^ static_cast<uint64_t>(trial));
}

// The validity rule: slip detected, an estimate, and the object still (less
// than max_motion and max_rotation_deg) until the slip was detected.
void Judge(const ProbeConfig& c, const ProbeRecording& rec, const estimator::TrialFriction& tr,
           ProbeTrialResult* r) {
  r->slip_detected = tr.slipped;
  r->mesh_triangle = tr.mesh_triangle;
  const int n = static_cast<int>(rec.motion.size());
  // Up to the sample where slip was detected: an object that breaks loose
  // while the probe's slip is still being established must not pass.
  const int last = tr.slipped ? std::clamp(tr.detection_index, 0, n - 1) : n - 1;
  for (int k = 0; k <= last; ++k) {
    r->object_motion_mm = std::max(r->object_motion_mm, 1e3 * rec.motion[k]);
    r->object_rotation_deg = std::max(r->object_rotation_deg, rec.rotation[k]);
  }
  if (!tr.slipped)
    r->invalid_reason = absl::StrFormat("no slip detected (mu >= %.3f)", tr.mu);
  else if (!tr.valid)
    r->invalid_reason = tr.message;
  else if (r->object_motion_mm >= 1e3 * c.max_motion)
    r->invalid_reason = absl::StrFormat("object moved %.2f mm before slip", r->object_motion_mm);
  else if (r->object_rotation_deg >= c.max_rotation_deg)
    r->invalid_reason =
        absl::StrFormat("object rotated %.2f deg before slip", r->object_rotation_deg);
  r->valid = r->invalid_reason.empty();
  if (r->valid) {
    r->mu_estimated = tr.mu;
    r->error = r->mu_slope - tr.mu;
  }
}

SurfaceSummary Summarize(const SurfacePair& s, const SlopeRow& ref,
                         const std::vector<ProbeTrialResult>& trials) {
  SurfaceSummary out;
  out.surface = s.name;
  out.mu_true = s.mu;
  out.mu_slope = ref.mu_slope;
  out.mu_plate_probe = ref.mu_probe;
  out.plate_probe_valid = ref.probe_valid;
  std::vector<double> est, err, abs_err;
  for (const ProbeTrialResult& t : trials) {
    ++out.trials;
    if (!t.valid) continue;
    ++out.valid;
    est.push_back(t.mu_estimated);
    err.push_back(t.error);
    abs_err.push_back(std::abs(t.error));
  }
  out.median_estimate = Median(est);
  out.median_signed_error = Median(err);
  out.median_abs_error = Median(abs_err);
  double sum = 0;
  for (double e : est) sum += e;
  out.mean_estimate = est.empty() ? 0 : sum / est.size();
  out.in_grasp_minus_plate = out.mean_estimate - out.mu_plate_probe;
  return out;
}

void Pool(ProbeReport* report) {
  ProbeSummary& s = report->summary;
  std::vector<double> err, abs_err;
  for (const ProbeTrialResult& t : report->trials) {
    ++s.trials;
    if (!t.valid) continue;
    ++s.valid;
    s.slip_detected_valid += t.slip_detected;
    err.push_back(t.error);
    abs_err.push_back(std::abs(t.error));
  }
  s.median_signed_error = Median(err);
  s.median_abs_error = Median(abs_err);
  double sum = 0;
  int n = 0;
  for (const SurfaceSummary& p : s.per_surface)
    if (p.valid > 0 && p.plate_probe_valid) sum += p.in_grasp_minus_plate, ++n;
  s.mean_in_grasp_minus_plate = n ? sum / n : 0;
}

}  // namespace

absl::Status ValidateSurfaces(const std::vector<SurfacePair>& surfaces) {
  if (surfaces.empty()) return absl::InvalidArgumentError("surfaces: empty");
  for (size_t i = 0; i < surfaces.size(); ++i)
    if (!(surfaces[i].mu >= 0.1 && surfaces[i].mu <= 1.5))
      return absl::InvalidArgumentError(
          absl::StrFormat("surfaces[%d].mu: must be in [0.1, 1.5], got %g", i, surfaces[i].mu));
  return absl::OkStatus();
}

absl::Status ValidateProbeConfig(const ProbeConfig& c) {
  auto bad = [](const char* f, const std::string& why) {
    return absl::InvalidArgumentError(absl::StrCat(f, ": ", why));
  };
  TF_RETURN_IF_ERROR(io::PrependPath(ValidateProbeObject(c.object), "object", "."));
  if (!(c.force_sigma >= 0 && c.force_sigma <= 5))
    return bad("force_sigma", absl::StrFormat("must be in [0, 5] N, got %g", c.force_sigma));
  if (!(c.force_bias >= 0 && c.force_bias <= 5))
    return bad("force_bias", absl::StrFormat("must be in [0, 5] N, got %g", c.force_bias));
  if (!(c.contact_sigma >= 0 && c.contact_sigma <= 0.005))
    return bad("contact_sigma",
               absl::StrFormat("must be in [0, 0.005] m, got %g", c.contact_sigma));
  if (!(c.hold_scale > 0 && c.hold_scale <= 3))
    return bad("hold_scale", absl::StrFormat("must be in (0, 3], got %g", c.hold_scale));
  if (!(c.table_mu > 0 && c.table_mu <= 2))
    return bad("table_mu", absl::StrFormat("must be in (0, 2], got %g", c.table_mu));
  if (!(c.max_motion > 0)) return bad("max_motion", "must be > 0 m");
  if (!(c.max_rotation_deg > 0)) return bad("max_rotation_deg", "must be > 0 deg");
  if (!(c.probe_travel_stop > c.slope.friction.slip_distance))
    return bad("probe_travel_stop", "must exceed the estimator's slip_distance");
  if (!(c.kp > 0)) return bad("kp", "must be > 0 N/m");
  if (!(c.admittance_gain >= 0 && c.admittance_gain <= 1))
    return bad("admittance_gain", "must be in [0, 1]");
  if (!(c.confidence >= 0)) return bad("confidence", "must be >= 0");
  if (!(c.plan_sigma >= 0)) return bad("plan_sigma", "must be >= 0 N");
  return ValidateSlopeConfig(c.slope);
}

absl::StatusOr<ProbeTrialResult> RunProbeTrial(const ProbeConfig& c, const SurfacePair& surface,
                                               int trial, double mu_slope) {
  const auto wall0 = std::chrono::steady_clock::now();
  TF_RETURN_IF_ERROR(ValidateProbeConfig(c));
  TF_RETURN_IF_ERROR(ValidateSurfaces({surface}));
  std::mt19937_64 rng(TrialSeed(c.seed, surface.name, trial));
  TF_ASSIGN_OR_RETURN(ProbeSetup setup, MakeProbeSetup(c, surface, rng));
  TF_ASSIGN_OR_RETURN(ProbeRecording rec, SimulateProbe(c, setup, rng));
  ProbeTrialResult r;
  r.surface = surface.name;
  r.trial = trial;
  r.mu_true = surface.mu;
  r.mu_slope = mu_slope;
  if (rec.dropped || rec.trial.samples.size() < 3) {
    r.invalid_reason =
        rec.dropped ? "object dropped (moved more than 20 mm)" : "probe never touched the object";
  } else {
    estimator::FrictionOptions options = c.slope.friction;
    options.mesh = BoxMesh(c.object.size);  // the normal from the nearest triangle, as in the paper
    TF_ASSIGN_OR_RETURN(estimator::FrictionEstimate est,
                        estimator::EstimateFriction({rec.trial}, options));
    Judge(c, rec, est.trials[0], &r);
  }
  r.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return r;
}

absl::StatusOr<ProbeReport> RunProbeExperiment(const ProbeConfig& c,
                                               const std::vector<SurfacePair>& surfaces, int trials,
                                               const std::function<void(int, int)>& progress) {
  const auto wall0 = std::chrono::steady_clock::now();
  if (trials < 1)
    return absl::InvalidArgumentError(absl::StrFormat("trials: must be >= 1, got %d", trials));
  TF_RETURN_IF_ERROR(ValidateProbeConfig(c));
  TF_RETURN_IF_ERROR(ValidateSurfaces(surfaces));
  ProbeReport report;
  const int total = trials * static_cast<int>(surfaces.size());
  for (const SurfacePair& surface : surfaces) {
    TF_ASSIGN_OR_RETURN(SlopeRow ref, RunSlopeAndProbe(c.slope, surface.mu));
    std::vector<ProbeTrialResult> rows;
    for (int k = 0; k < trials; ++k) {
      TF_ASSIGN_OR_RETURN(ProbeTrialResult r, RunProbeTrial(c, surface, k, ref.mu_slope));
      rows.push_back(r);
      report.trials.push_back(std::move(r));
      if (progress) progress(static_cast<int>(report.trials.size()), total);
    }
    report.summary.per_surface.push_back(Summarize(surface, ref, rows));
  }
  Pool(&report);
  report.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return report;
}

}  // namespace tactforce::experiment
