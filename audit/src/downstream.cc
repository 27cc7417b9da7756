// Downstream gain: force-estimation error of the grasp estimator when taxel
// readings are corrected with the extended model vs the nominal one.
//
// Simulated grasps (planner::MakeRandomGrasp, feasible, intrinsic contacts
// only) are planned; each contact's true normal force is loaded in a 0.5 s
// ramp and held 0.5 s, and its reading is produced by the EXTENDED model
// (the audit's best description of the sensor) plus its noise. Readings are
// corrected back to N by the nominal affine model, or by the extended model
// (sim::CorrectReading; the hysteresis correction assumes the loading
// branch, +width/2), then fed to estimator::EstimateForces. Error = RMS over
// contacts of |f_est - f_true|. Because the readings come from the extended
// model this measures what the correction buys IF the extended model is
// right; the held-out gain measures whether it is.
#include <cmath>
#include <random>

#include "absl/strings/str_cat.h"
#include "audit_internal.h"
#include "tactforce/estimator/force_estimation.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"

namespace tactforce::audit::internal {

absl::StatusOr<DownstreamGain> MeasureDownstreamGain(const sim::SensorModel& nominal,
                                                     const sim::SensorModel& extended, int grasps,
                                                     uint64_t seed, double max_force) {
  if (grasps <= 0) return absl::InvalidArgumentError("downstream_grasps: must be > 0");
  if (nominal.gain == 0 || extended.gain == 0)
    return absl::InvalidArgumentError("model gain is zero");
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> gauss(0, 1);
  planner::RandomGraspOptions go;
  go.extrinsic_probability = 0;
  go.infeasible_fraction = 0;
  go.max_contacts = 4;
  go.max_mass = 0.5;
  double se_nom = 0, se_ext = 0, se_est = 0;
  int contacts = 0, done = 0;
  const double rate = 200, ramp = 0.5, hold = 0.5;
  const int n = static_cast<int>((ramp + hold) * rate) + 1;
  std::vector<double> t(n), f(n), s(n);
  for (int k = 0; k < n; ++k) t[k] = k / rate;
  for (int attempt = 0; attempt < 10 * grasps && done < grasps; ++attempt) {
    planner::RandomGrasp g = planner::MakeRandomGrasp(rng, go);
    auto plan = planner::Plan(g.problem, planner::PlanOptions{}, planner::SolverKind::kGeometric);
    if (!plan.ok() || plan->status != planner::PlanStatus::kOptimal) continue;
    bool in_range = true;
    for (double fn : plan->normal_forces) in_range = in_range && fn <= max_force;
    if (!in_range) continue;
    std::vector<double> exact = plan->normal_forces;
    std::vector<double> r_nom, r_ext;
    for (size_t c = 0; c < g.problem.contacts.size(); ++c) {
      const auto& ct = g.problem.contacts[c];
      const double fn = plan->normal_forces[c];
      const double shear = (plan->forces[c] - fn * ct.normal).norm();
      for (int k = 0; k < n; ++k) {
        const double u = std::min(1.0, t[k] / ramp);
        f[k] = fn * (0.5 - 0.5 * std::cos(M_PI * u));
        s[k] = shear * (0.5 - 0.5 * std::cos(M_PI * u));
      }
      const auto pred = sim::PredictReading(extended, t, f, s);
      const double reading = pred.back() + extended.gain * extended.noise * gauss(rng);
      r_nom.push_back((reading - nominal.offset) / nominal.gain);
      double corrected = sim::CorrectReading(extended, reading, t.back(), shear);
      if (extended.effects.hysteresis_width > 0 && corrected > 0)
        corrected += 0.5 * extended.effects.hysteresis_width;
      r_ext.push_back(corrected);
    }
    auto e_nom = estimator::EstimateForces(g.problem, r_nom);
    auto e_ext = estimator::EstimateForces(g.problem, r_ext);
    auto e_ref = estimator::EstimateForces(g.problem, exact);
    if (!e_nom.ok() || !e_ext.ok() || !e_ref.ok() ||
        e_nom->status != estimator::EstimateStatus::kOk ||
        e_ext->status != estimator::EstimateStatus::kOk ||
        e_ref->status != estimator::EstimateStatus::kOk)
      continue;
    for (size_t c = 0; c < g.problem.contacts.size(); ++c) {
      se_nom += (e_nom->forces[c] - e_ref->forces[c]).squaredNorm();
      se_ext += (e_ext->forces[c] - e_ref->forces[c]).squaredNorm();
      se_est += (e_ref->forces[c] - plan->forces[c]).squaredNorm();
      ++contacts;
    }
    ++done;
  }
  if (done == 0)
    return absl::InternalError(absl::StrCat(
        "downstream gain: no simulated grasp with normal forces within the measured range (<= ",
        max_force, " N) could be planned and estimated"));
  DownstreamGain dg;
  dg.grasps = done;
  dg.method = "projection (GeoDEx Problem 1) on simulated random grasps";
  dg.error_nominal = std::sqrt(se_nom / contacts);
  dg.error_extended = std::sqrt(se_ext / contacts);
  dg.error_exact_readings = std::sqrt(se_est / contacts);
  dg.gain = dg.error_nominal > 0 ? 100 * (1 - dg.error_extended / dg.error_nominal) : 0;
  return dg;
}

}  // namespace tactforce::audit::internal
