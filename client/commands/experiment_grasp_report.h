// `tactforce experiment grasp`'s Table III report: per object and feedback
// the success count, the force error split between successful and failed
// trials and the failure causes, beside GeoDEx's numbers; and the JSON
// members the batch rows add for it.
#pragma once

#include <string>
#include <vector>

#include "tactforce/experiment/grasp.h"

namespace tactforce::cli {

// The paper's Table III / Sec. IV-C values for one object and feedback mode
// ("-" where the paper gives none in its text).
struct PaperGraspValues {
  std::string success;      // "8/10"
  std::string force_error;  // "0.09 +- 0.04 N (converged)"
};
PaperGraspValues PaperGraspValuesFor(experiment::GraspObject object, experiment::Feedback feedback);

// Rows: object, feedback, successes/trials, force error success (mean +- std),
// failure (mean +- std), causes, and the paper's values; then, with the paper
// protocol, the switched phase's force error per fingertip.
std::string GraspSplitTable(const std::vector<experiment::BatchSummary>& rows, bool switched);

// ,"force_error_success":..,"force_error_success_std":..,"force_error_failure":..,
// "force_error_failure_std":..,"failure_causes":{..},"replan_failures":..,
// "contact_location_error_mean":..,"switched_force_error":[..] (no braces).
std::string GraspSplitJsonMembers(const experiment::BatchSummary& row);

}  // namespace tactforce::cli
