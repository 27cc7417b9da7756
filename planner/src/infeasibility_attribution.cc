// ForceSolver::AttributeInfeasibility (solver.h): which uncertainty source
// made a plan infeasible, found by solving again without each source.
#include <chrono>
#include <string>

#include "absl/strings/str_cat.h"
#include "tactforce/planner/parameter_uncertainty.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/validation.h"

namespace tactforce::planner {
namespace {

PlanProblem WithoutParameters(PlanProblem p) {
  p.object.uncertainty.covariance.setZero();
  return p;
}

PlanProblem WithoutFriction(PlanProblem p) {
  for (Contact& c : p.contacts) c.friction_sigma = 0.0;
  return p;
}

PlanProblem WithoutMeasurement(PlanProblem p) {
  for (Contact& c : p.contacts) c.sigma = 0.0;
  return p;
}

const char* SourceName(UncertaintySource s) {
  switch (s) {
    case UncertaintySource::kParameters:
      return "inertial-parameter (mass, CoM, inertia) uncertainty";
    case UncertaintySource::kFriction:
      return "friction uncertainty";
    case UncertaintySource::kMeasurement:
      return "measurement noise";
    default:
      return "uncertainty";
  }
}

// The contact on which `source` takes the largest margin.
int DominantContact(const PlanProblem& problem, const std::vector<RowMargin>& margins,
                    UncertaintySource source, const PlanOptions& options) {
  int best = 0;
  double largest = -1.0;
  if (source == UncertaintySource::kFriction) {
    for (int i = 0; i < static_cast<int>(problem.contacts.size()); ++i) {
      const double cut = options.confidence * problem.contacts[i].friction_sigma;
      if (cut > largest) largest = cut, best = i;
    }
    return best;
  }
  for (const RowMargin& m : margins) {
    const double v = source == UncertaintySource::kParameters ? m.parameters : m.measurement;
    if (v > largest) largest = v, best = m.contact;
  }
  return best;
}

}  // namespace

void ForceSolver::AttributeInfeasibility(const PlanProblem& problem, const PlanOptions& options,
                                         const SolveControl& control, PlanResult* result) const {
  // Each candidate is a new problem (a source removed): validated, solved
  // and finished, never attributed itself.
  const auto feasible = [&](const PlanProblem& q) {
    PlanningWorkspace workspace;
    PlanResult r;
    return ValidateProblem(q, options, &workspace.prepared.problem).ok() &&
           SolveValidated(options, control, std::chrono::steady_clock::now(), &workspace, &r)
               .ok() &&
           r.status == PlanStatus::kOptimal;
  };
  if (!feasible(WithoutMeasurement(WithoutFriction(WithoutParameters(problem))))) {
    result->infeasible_source = UncertaintySource::kNominal;
    absl::StrAppend(&result->message, "; infeasible even without any uncertainty");
    return;
  }
  const std::pair<UncertaintySource, PlanProblem> candidates[] = {
      {UncertaintySource::kParameters, WithoutParameters(problem)},
      {UncertaintySource::kFriction, WithoutFriction(problem)},
      {UncertaintySource::kMeasurement, WithoutMeasurement(problem)}};
  std::string also;
  for (const auto& [source, without] : candidates) {
    if (!feasible(without)) continue;
    if (result->infeasible_source == UncertaintySource::kNone) {
      result->infeasible_source = source;
    } else {
      absl::StrAppend(&also, also.empty() ? "" : " or ", SourceName(source));
    }
  }
  if (result->infeasible_source == UncertaintySource::kNone) {
    result->infeasible_source = UncertaintySource::kCombined;
    absl::StrAppend(
        &result->message,
        "; infeasible because of the uncertainty sources together (removing any one alone "
        "does not help)");
    return;
  }
  const int contact =
      DominantContact(problem, result->row_margins, result->infeasible_source, options);
  absl::StrAppend(&result->message, "; infeasible because of the ",
                  SourceName(result->infeasible_source), ", largest on ",
                  ContactLabel(problem, contact), " (feasible without it",
                  also.empty() ? "" : absl::StrCat("; also feasible without the ", also), ")");
}

}  // namespace tactforce::planner
