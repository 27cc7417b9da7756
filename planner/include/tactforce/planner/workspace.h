// PlanningWorkspace: every buffer the geometric path (and force estimation)
// needs, kept from solve to solve (in the manner of ProxSuite's workspace).
//
//   PlanningWorkspace workspace;           // one per thread / stream / worker
//   PlanResult result;                     // reused too
//   absl::Status s = solver.Solve(problem, options, &workspace, &result);
//
// Storage grows to the largest problem seen and is kept; once a workspace
// and a result have served a problem with the same contact count, cone sides
// and active-set size, a GEOMETRIC solve that ends OPTIMAL allocates nothing
// (tests/planner/workspace_test.cc counts). Messages of infeasible or failed
// solves and the IPOPT / CROSS_CHECK backends still allocate.
//
// Not thread-safe: a workspace serves one solve at a time. Contents between
// solves are scratch, except `prepared`, which describes the last solve.
#pragma once

#include <Eigen/Core>

#include "tactforce/planner/dense_qp.h"
#include "tactforce/planner/force_model.h"

namespace tactforce::planner {

struct PlanningWorkspace {
  PreparedProblem prepared;  // the last request, validated and prepared
  EquilibriumScratch equilibrium_scratch;
  DenseQp qp;  // the FE-plane QP of the last solve
  DenseQpWorkspace qp_workspace;
  DenseQpResult qp_result;
  Eigen::VectorXd forces;  // 3n stacked forces (N)
};

}  // namespace tactforce::planner
