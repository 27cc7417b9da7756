// The Plan RPC's library path for the fuzz targets: what the server's
// Plan handler runs (api::PreparePlan with the default CallLimits, then
// api::SolvePlan, which validates and solves), always on the GEOMETRIC
// backend: Ipopt is slow and serialised, and CROSS_CHECK includes it.
#pragma once

#include "tactforce/v1/planner.pb.h"

namespace tactforce::fuzz {

void RunPlanRequest(const v1::PlanRequest& request);

}  // namespace tactforce::fuzz
