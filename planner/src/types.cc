// PlanOptions::IsValid() and the names of the planner's enums.
#include "tactforce/planner/types.h"

#include <cmath>
#include <utility>

#include "absl/strings/str_cat.h"

namespace tactforce::planner {

bool PlanOptions::IsValid(std::string* error) const {
  auto fail = [&](std::string what) {
    if (error != nullptr) *error = std::move(what);
    return false;
  };
  if (cone_sides < kMinConeSides || cone_sides > kMaxConeSides) {
    return fail(absl::StrCat("cone_sides: must be in ", kMinConeSides, "..", kMaxConeSides));
  }
  if (!std::isfinite(confidence) || confidence < 0.0 || confidence > kMaxConfidence)
    return fail(
        absl::StrCat("confidence: must be in 0..", kMaxConfidence, " (got ", confidence, ")"));
  if (!std::isfinite(rank_tolerance) || rank_tolerance <= 0.0 || rank_tolerance >= 1e-2)
    return fail("rank_tolerance: must be in (0, 1e-2)");
  if (max_contacts < 1) return fail("max_contacts: must be >= 1");
  if (!(ipopt.tolerance > 0.0) || !std::isfinite(ipopt.tolerance))
    return fail("ipopt_tolerance: must be finite and > 0");
  if (ipopt.max_iterations < 1) return fail("ipopt_max_iterations: must be >= 1");
  if (!std::isfinite(ipopt.max_cpu_seconds) || ipopt.max_cpu_seconds < 0.0)
    return fail("ipopt_max_cpu_seconds: must be finite and >= 0");
  if (!(agreement_tolerance > 0.0) || !std::isfinite(agreement_tolerance))
    return fail("agreement_tolerance: must be finite and > 0");
  return true;
}

const char* ToString(PlanStatus status) {
  switch (status) {
    case PlanStatus::kOptimal:
      return "OPTIMAL";
    case PlanStatus::kInfeasible:
      return "INFEASIBLE";
    case PlanStatus::kSolverFailure:
      return "SOLVER_FAILURE";
  }
  return "UNKNOWN";
}

const char* ToString(SolverKind solver) {
  switch (solver) {
    case SolverKind::kGeometric:
      return "GEOMETRIC";
    case SolverKind::kIpopt:
      return "IPOPT";
    case SolverKind::kCrossCheck:
      return "CROSS_CHECK";
  }
  return "UNKNOWN";
}

}  // namespace tactforce::planner
