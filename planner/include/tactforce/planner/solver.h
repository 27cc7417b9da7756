// One interface, several backends (modelled on Drake's SolverBase):
// the non-virtual Solve() validates the request, prepares the shared
// geometry, times the work, calls the backend's DoSolve() and fills the
// reported quantities (normal forces, margins, sigmas) the same way for all.
// Each request is checked once: a front end that validates early
// (ValidatePlan, validation.h) passes the ValidatedPlan down, and CROSS_CHECK
// runs its two backends' DoSolve on the one prepared workspace.
//
//   auto solver = MakeSolver(SolverKind::kGeometric);
//   absl::StatusOr<PlanResult> r = solver->Solve(problem, options);
//   // !r.ok(): bad input (InvalidArgument naming the field)
//   // r->status: kOptimal, kInfeasible (with a message), kSolverFailure
//
// In a control loop, keep a PlanningWorkspace and a PlanResult and use the
// in-place Solve: same validation, answers and result, no allocation once
// warm (see workspace.h).
#pragma once

#include <chrono>
#include <memory>

#include "absl/status/statusor.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/types.h"
#include "tactforce/planner/validation.h"
#include "tactforce/planner/workspace.h"

namespace tactforce::planner {

class ForceSolver {
 public:
  virtual ~ForceSolver() = default;
  ForceSolver(const ForceSolver&) = delete;
  ForceSolver& operator=(const ForceSolver&) = delete;

  SolverKind kind() const { return kind_; }

  absl::StatusOr<PlanResult> Solve(const PlanProblem& problem, const PlanOptions& options,
                                   const SolveControl& control = {}) const;
  // In place: `result` is overwritten (its storage reused) and is
  // meaningful only when the returned status is OK. `problem` must not live
  // inside `workspace`.
  absl::Status Solve(const PlanProblem& problem, const PlanOptions& options,
                     PlanningWorkspace* workspace, PlanResult* result,
                     const SolveControl& control = {}) const;
  // A plan validated already (ValidatePlan): prepared and solved, nothing
  // checked again but whether this backend supports its options.
  // InvalidArgument when `plan` holds nothing validated.
  absl::Status Solve(const ValidatedPlan& plan, PlanningWorkspace* workspace, PlanResult* result,
                     const SolveControl& control = {}) const;

 protected:
  explicit ForceSolver(SolverKind kind) : kind_(kind) {}

  // Rejects options this backend cannot honour (InvalidArgument).
  virtual absl::Status CheckSupported(const PlanOptions& options) const { return absl::OkStatus(); }
  // From workspace->prepared, fills status, message, forces (one per
  // contact; empty unless optimal), iterations and, where meaningful,
  // geometric / cross_check / ipopt. `result` arrives reset (status
  // kSolverFailure, empty vectors and message).
  virtual void DoSolve(const PlanOptions& options, const SolveControl& control,
                       PlanningWorkspace* workspace, PlanResult* result) const = 0;

  // For a backend built on others (CROSS_CHECK): `backend` on the problem
  // already prepared in `workspace`, its answer finished, timed and (when
  // infeasible under model uncertainty) attributed exactly as its own
  // Solve would. Leaves workspace->prepared unchanged.
  static void SolvePrepared(const ForceSolver& backend, const PlanOptions& options,
                            const SolveControl& control, PlanningWorkspace* workspace,
                            PlanResult* result);

 private:
  // From workspace->prepared.problem, validated: support check, preparation,
  // DoSolve, the reported quantities, the time since `start`.
  absl::Status SolveValidated(const PlanOptions& options, const SolveControl& control,
                              std::chrono::steady_clock::time_point start,
                              PlanningWorkspace* workspace, PlanResult* result) const;
  // DoSolve and the reported quantities on the prepared workspace.
  void SolveAndFinish(const PlanOptions& options, const SolveControl& control,
                      PlanningWorkspace* workspace, PlanResult* result) const;
  // A plan with model uncertainty found infeasible: which source's
  // tightening, removed alone, makes it feasible (types.h UncertaintySource).
  void AttributeInfeasibility(const PlanProblem& problem, const PlanOptions& options,
                              const SolveControl& control, PlanResult* result) const;

  SolverKind kind_;
};

// Backends. All are stateless and safe to share between threads.
std::unique_ptr<ForceSolver> MakeSolver(SolverKind kind);

// The process's shared solver of each kind (stateless, thread-safe).
const ForceSolver& CachedSolver(SolverKind kind);

// Convenience: CachedSolver(kind).Solve(...), one-off or in place.
absl::StatusOr<PlanResult> Plan(const PlanProblem& problem, const PlanOptions& options,
                                SolverKind kind, const SolveControl& control = {});
absl::Status Plan(const PlanProblem& problem, const PlanOptions& options, SolverKind kind,
                  PlanningWorkspace* workspace, PlanResult* result,
                  const SolveControl& control = {});

}  // namespace tactforce::planner
