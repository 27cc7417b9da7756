// Plain-text rendering of a plan for people (the CLI's `--format table`).
#pragma once

#include <string>

#include "tactforce/api/names.h"  // StatusName, SolverName (also for the table's readers)
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {

// Status and message; one row per contact (name, force x/y/z, normal force,
// sigma); objective, min margin, solver, time (us), iterations; and a
// cross-check line when the response has one. Contact names come from the
// request (index when unnamed). Ends with a newline.
std::string FormatPlanTable(const v1::PlanRequest& request, const v1::PlanResponse& response);

}  // namespace tactforce::api
