// What plan_plot.h draws, derived from the request through the planner
// library (validation, Prepare: the same ellipsoid and tightening the solve
// used) and the response's forces.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <tuple>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "tactforce/api/convert.h"
#include "tactforce/api/names.h"
#include "tactforce/api/plan_plot.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/validation.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::api {
namespace {

// The drawn apex shift (N) of every contact: EXACT, cone_shift / mu (the
// tightened cone itself); PYRAMID, the largest facet tightening
// (nominal_rhs - rhs) over the facet row's normal component mu cos(pi / k).
std::vector<double> ApexShifts(const planner::PreparedProblem& prepared,
                               const planner::PlanOptions& options) {
  const int n = prepared.num_contacts();
  std::vector<double> shift(n, 0.0);
  if (options.cone == planner::ConeModel::kExact) {
    for (int i = 0; i < n && i < static_cast<int>(prepared.cone_shift.size()); ++i) {
      const double mu = prepared.problem.contacts[i].friction;
      shift[i] = mu > 0 ? prepared.cone_shift[i] / mu : 0.0;
    }
    return shift;
  }
  const double cos_half = std::cos(std::numbers::pi / options.cone_sides);
  const planner::ConstraintRows& rows = prepared.rows;
  for (size_t r = 0; r < rows.info.size(); ++r) {
    if (rows.info[r].kind != planner::RowKind::kFrictionFacet) continue;
    const int i = rows.info[r].contact;
    const double k = prepared.problem.contacts[i].friction * cos_half;
    if (k > 0) shift[i] = std::max(shift[i], (rows.nominal_rhs(r) - rows.rhs(r)) / k);
  }
  return shift;
}

std::string Settings(const planner::PlanOptions& options, const v1::PlanResponse& response,
                     int contacts) {
  const std::string cone = options.cone == planner::ConeModel::kExact
                               ? std::string("exact cones")
                               : absl::StrCat(options.cone_sides, "-facet pyramids");
  return absl::StrFormat("%d contacts, %s, confidence %g, solver %s", contacts, cone,
                         options.confidence, SolverName(response.solver()));
}

std::string Outcome(const v1::PlanResponse& response) {
  std::string out;
  if (response.status() == v1::PLAN_STATUS_OPTIMAL) {
    out = absl::StrFormat("objective %.4g N\xc2\xb2, min margin %.4g N", response.objective(),
                          response.min_margin());
  }
  if (!response.message().empty())
    absl::StrAppend(&out, out.empty() ? "" : "; ", response.message());
  return out;
}

}  // namespace

absl::StatusOr<PlanScene> BuildPlanScene(const planner::PlanProblem& problem,
                                         const planner::PlanOptions& options,
                                         const v1::PlanResponse& response) {
  TF_ASSIGN_OR_RETURN(planner::PlanProblem validated, planner::ValidateProblem(problem, options));
  const planner::PreparedProblem prepared = planner::Prepare(std::move(validated), options);
  const int n = prepared.num_contacts();
  const std::vector<double> shift = ApexShifts(prepared, options);
  const bool forces = response.forces_size() == n;
  PlanScene scene;
  scene.status = StatusName(response.status());
  scene.settings = Settings(options, response, n);
  scene.outcome = Outcome(response);
  if (!forces)
    absl::StrAppend(&scene.outcome, scene.outcome.empty() ? "" : "; ", "no forces in the response");
  scene.com = prepared.problem.object.com;
  scene.gravity = prepared.problem.object.gravity;
  for (int i = 0; i < n; ++i) {
    const planner::Contact& c = prepared.problem.contacts[i];
    ContactGlyph g;
    g.label = c.name.empty() ? absl::StrCat("contact ", i) : c.name;
    g.position = c.position;
    g.normal = c.normal;
    std::tie(g.tangent1, g.tangent2) = planner::TangentBasis(c.normal);
    g.friction = c.friction;
    g.cone_sides = options.cone == planner::ConeModel::kExact ? 0 : options.cone_sides;
    g.apex_shift = shift[i];
    g.has_force = forces;
    if (forces) g.force = FromProto(response.forces(i));
    g.covariance = prepared.ellipsoid.ContactCovariance(i);
    if (prepared.parameters.active)
      g.parameter_covariance = prepared.parameters.contact_covariance[i];
    scene.contacts.push_back(std::move(g));
  }
  return scene;
}

std::vector<int> PlottedSteps(int steps, int max_steps) {
  std::vector<int> out;
  if (steps <= 0) return out;
  max_steps = std::max(max_steps, 2);
  if (steps <= max_steps) {
    for (int k = 0; k < steps; ++k) out.push_back(k);
    return out;
  }
  for (int j = 0; j < max_steps; ++j) {
    const int k =
        static_cast<int>(std::lround(static_cast<double>(j) * (steps - 1) / (max_steps - 1)));
    if (out.empty() || out.back() != k) out.push_back(k);
  }
  return out;
}

}  // namespace tactforce::api
