// RunChain: per object and seed, the in-grasp friction probe and the in-hand
// inertia fit on the object's simulated equivalents (chain.h), then three
// closed-loop grasp batches planned with the truth, the point estimates and
// the estimates with their uncertainty; rows per object and planning.
#include "tactforce/experiment/chain.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "grasp_internal.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::experiment {
namespace {

using planner::Vec3;

struct Truth {
  double mass = 0, mu = 0;
  Vec3 com = Vec3::Zero();
  planner::Inertia inertia;
};

// The simulated object's parameters, as GraspSetup builds it.
absl::StatusOr<Truth> ObjectTruth(const ChainConfig& config, GraspObject object) {
  GraspConfig gc = config.grasp;
  gc.object = object;
  gc.planning_model.reset();
  TF_ASSIGN_OR_RETURN(std::unique_ptr<GraspSetup> setup, GraspSetup::Create(gc));
  const GraspSetup::Impl& im = setup->impl();
  return Truth{im.base.object.mass, im.base.contacts.front().friction, im.base.object.com,
               im.inertia};
}

double Median(std::vector<double> v) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The in-grasp probe on the probe's box with the object's fingertip mu:
// mean and sample std. dev. over the valid trials (FrictionEstimate's rule).
absl::Status ProbeFriction(const ChainConfig& config, uint64_t seed, ChainEstimates* e) {
  ProbeConfig pc = config.probe;
  pc.seed = seed;
  const SurfacePair surface{absl::StrCat(ToString(e->object), "-fingertip"), e->mu_true};
  std::vector<double> mus;
  for (int k = 0; k < config.probe_trials; ++k) {
    TF_ASSIGN_OR_RETURN(ProbeTrialResult t, RunProbeTrial(pc, surface, k, e->mu_true));
    if (t.valid) mus.push_back(t.mu_estimated);
  }
  e->probes_valid = static_cast<int>(mus.size());
  if (mus.size() < 2)
    return absl::FailedPreconditionError(
        absl::StrFormat("probe: %d of %d probes valid on %s (seed %d); need 2 for a spread",
                        mus.size(), config.probe_trials, ToString(e->object), seed));
  double sum = 0, sq = 0;
  for (double m : mus) sum += m;
  e->mu = sum / mus.size();
  for (double m : mus) sq += (m - e->mu) * (m - e->mu);
  e->mu_sigma = std::sqrt(sq / (mus.size() - 1));
  return absl::OkStatus();
}

// The in-hand run on the object's equivalent box and the fit.
absl::StatusOr<inertia::InertiaFit> FitInHand(const ChainConfig& config, uint64_t seed,
                                              const Truth& truth, GraspObject object) {
  InHandConfig ic = config.inhand;
  ic.custom = InHandEquivalent(ToString(object), truth.mass, truth.com, truth.inertia);
  ic.seed = seed;
  ic.duration = config.inhand_duration;
  absl::StatusOr<InHandRun> run = RunInHand(ic);
  if (!run.ok()) return io::PrependPath(run.status(), "inhand");
  absl::StatusOr<inertia::InertiaFit> fit =
      inertia::FitInertia(run->samples, InHandFitOptions(*run, config.fit_method));
  if (!fit.ok()) return io::PrependPath(fit.status(), "fit");
  return fit;
}

void FillModels(const ChainConfig& config, const inertia::InertiaFit& fit, ChainEstimates* e) {
  e->mass = fit.params.mass;
  e->mass_se = fit.mass_se;
  e->com = fit.params.com;
  e->com_se = fit.com_se;
  const inertia::InertiaTensor& I = fit.params.inertia_com;
  PlanningModel point;
  point.mass = fit.params.mass;
  point.com = fit.params.com;
  point.inertia = {I.ixx, I.iyy, I.izz, I.ixy, I.ixz, I.iyz};
  point.friction = e->mu;
  e->point = point;
  PlanningModel uncertain = point;
  uncertain.friction_sigma = e->mu_sigma;
  uncertain.uncertainty.covariance = fit.covariance;
  uncertain.uncertainty.confidence = config.confidence;
  e->uncertain = uncertain;
  bool off =
      std::abs(e->mu - e->mu_true) > e->mu_sigma || std::abs(e->mass - e->mass_true) > e->mass_se;
  for (int k = 0; k < 3; ++k) off = off || std::abs(e->com[k] - e->com_true[k]) > e->com_se[k];
  e->off_by_more_than_se = off;
}

absl::StatusOr<ChainEstimates> Estimate(const ChainConfig& config, GraspObject object,
                                        uint64_t seed, const Truth& truth) {
  ChainEstimates e;
  e.object = object;
  e.seed = seed;
  e.mu_true = truth.mu;
  e.mass_true = truth.mass;
  e.com_true = truth.com;
  TF_RETURN_IF_ERROR(ProbeFriction(config, seed, &e));
  TF_ASSIGN_OR_RETURN(inertia::InertiaFit fit, FitInHand(config, seed, truth, object));
  FillModels(config, fit, &e);
  return e;
}

// One batch into its row; an infeasible plan counts its trials as failures.
absl::Status RunPlanned(const ChainConfig& config, const ChainEstimates& e, ChainRow* row,
                        std::vector<double>* squeezes, std::vector<double>* margins) {
  GraspConfig gc = config.grasp;
  gc.object = e.object;
  gc.seed = e.seed;
  if (row->planning == Planning::kPoint) gc.planning_model = e.point;
  if (row->planning == Planning::kUncertain) gc.planning_model = e.uncertain;
  row->trials += config.trials;
  row->estimates_off = row->estimates_off || e.off_by_more_than_se;
  absl::StatusOr<BatchSummary> b = RunGraspBatch(gc, config.trials);
  if (!b.ok() && b.status().code() == absl::StatusCode::kFailedPrecondition) {
    if (row->plan_failures++ == 0) row->plan_failure = std::string(b.status().message());
    return absl::OkStatus();
  }
  TF_RETURN_IF_ERROR(b.status());
  row->successes += b->successes;
  row->trials_run += b->trials;
  for (const TrialResult& t : b->results) {
    squeezes->push_back(t.squeeze);
    margins->push_back(t.min_slip_margin);
    row->min_slip_margin = std::min(row->min_slip_margin, t.min_slip_margin);
  }
  return absl::OkStatus();
}

}  // namespace

const char* ToString(Planning p) {
  switch (p) {
    case Planning::kTruth:
      return "truth";
    case Planning::kPoint:
      return "point";
    case Planning::kUncertain:
      return "uncertain";
  }
  return "?";
}

absl::Status ValidateChainConfig(const ChainConfig& c) {
  auto at_least = [](const char* field, double v, double lo) -> absl::Status {
    if (!(v >= lo))
      return absl::InvalidArgumentError(absl::StrFormat("%s: must be >= %g, got %g", field, lo, v));
    return absl::OkStatus();
  };
  if (c.objects.empty()) return absl::InvalidArgumentError("objects: empty");
  for (auto [f, v, lo] : {std::tuple{"seeds", double(c.seeds), 1.0},
                          {"trials", double(c.trials), 1.0},
                          {"probe_trials", double(c.probe_trials), 2.0},
                          {"inhand_duration", c.inhand_duration, 1.0},
                          {"confidence", c.confidence, 0.0}})
    TF_RETURN_IF_ERROR(at_least(f, v, lo));
  if (!std::isfinite(c.confidence) || c.confidence > planner::PlanOptions::kMaxConfidence)
    return absl::InvalidArgumentError(
        absl::StrFormat("confidence: must be finite and <= %g, got %g",
                        planner::PlanOptions::kMaxConfidence, c.confidence));
  TF_RETURN_IF_ERROR(ValidateGraspConfig(c.grasp));
  TF_RETURN_IF_ERROR(ValidateProbeConfig(c.probe));
  return absl::OkStatus();
}

InHandObject InHandEquivalent(const std::string& name, double mass, const Vec3& com,
                              const planner::Inertia& inertia) {
  // A uniform box has I_xx = m (y^2 + z^2) / 12, so x^2 = 6 (I_yy + I_zz - I_xx) / m.
  const double ix = inertia.ixx, iy = inertia.iyy, iz = inertia.izz;
  auto edge = [&](double a, double b, double c) {
    return std::clamp(std::sqrt(std::max(0.0, 6 * (b + c - a) / mass)), 0.04, 0.3);
  };
  InHandObject o;
  o.name = name;
  o.mass = mass;
  o.center = com;
  o.dimensions = Eigen::Vector3d(edge(ix, iy, iz), edge(iy, iz, ix), edge(iz, ix, iy));
  return o;
}

absl::StatusOr<ChainReport> RunChain(const ChainConfig& config,
                                     const std::function<void(int, int)>& progress) {
  TF_RETURN_IF_ERROR(ValidateChainConfig(config));
  const auto start = std::chrono::steady_clock::now();
  ChainReport report;
  const int total = static_cast<int>(config.objects.size()) * config.seeds * 4;
  int done = 0;
  for (GraspObject object : config.objects) {
    TF_ASSIGN_OR_RETURN(Truth truth, ObjectTruth(config, object));
    std::vector<ChainRow> rows(3);
    std::vector<std::vector<double>> squeezes(3), margins(3);
    for (int p = 0; p < 3; ++p)
      rows[p].object = object, rows[p].planning = static_cast<Planning>(p);
    for (int s = 0; s < config.seeds; ++s) {
      TF_ASSIGN_OR_RETURN(ChainEstimates e, Estimate(config, object, config.seed + s, truth));
      if (progress) progress(++done, total);
      for (int p = 0; p < 3; ++p) {
        TF_RETURN_IF_ERROR(RunPlanned(config, e, &rows[p], &squeezes[p], &margins[p]));
        if (progress) progress(++done, total);
      }
      report.estimates.push_back(e);
    }
    for (int p = 0; p < 3; ++p) {
      rows[p].median_squeeze_n = Median(squeezes[p]);
      rows[p].median_trial_slip_margin = Median(margins[p]);
      report.rows.push_back(rows[p]);
    }
  }
  report.wall_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace tactforce::experiment
