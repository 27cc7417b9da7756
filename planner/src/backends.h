// Internal: the concrete backends behind MakeSolver().
#pragma once

#include <memory>

#include "tactforce/planner/solver.h"

namespace tactforce::planner::internal {

std::unique_ptr<ForceSolver> MakeGeometricSolver();
std::unique_ptr<ForceSolver> MakeIpoptSolver();
std::unique_ptr<ForceSolver> MakeCrossCheckSolver();

}  // namespace tactforce::planner::internal
