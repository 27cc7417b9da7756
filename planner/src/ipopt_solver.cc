// Ipopt reference backend (SolverKind::kIpopt): the driver. It builds the
// NLP (ipopt_formulation.h), poses it to Ipopt through ForceNlp
// (ipopt_nlp.h) and turns the runs into a PlanResult. An independent check
// of the geometric backend: the same problem in the full 3n force space,
// solved by a general interior-point NLP solver (Ipopt 3.11, MUMPS).
//
// When the equilibrium leaves no freedom at all (e.g. a single contact) the
// unique equilibrium is checked directly, without Ipopt.
//
// A run that stalls at a cone apex (see ipopt_nlp.h) is accepted only if the
// barrier parameter is at its final value and the forces meet every
// constraint (checked here; the message says so). Those plans are feasible
// but their optimality is not certified: on random grasps they were within
// ~1e-4 N of the optimum.
//
// Infeasible problems. (1) The first run uses expect_infeasible_problem =
// yes and at most kFirstRunIterations iterations; without the heuristic an
// infeasible EXACT problem could take thousands of iterations. Every
// constraint is convex, so its Infeasible_Problem_Detected is trusted. (2)
// A first run that ends any other way without an optimum is followed by the
// always-feasible phase-one problem min t >= 0 with every inequality
// relaxed by t (equilibrium exact): a least violation above
// kInfeasibilityTolerance * max(1, largest bound) N means infeasible;
// otherwise (3) the problem is solved again from the phase-one point with
// the full iteration budget and the heuristic off.
//
// Ipopt settings (all explicit; no ipopt.opt file is read):
//   tol                 options.ipopt.tolerance (scaled overall NLP error)
//   max_iter            options.ipopt.max_iterations per run (the first
//                       run: at most kFirstRunIterations)
//   print_level 0, sb yes, and no console journal: Ipopt never prints.
//   linear_solver       mumps (the only one in Debian's build), with
//   mumps_pivot_order   0 (AMD): fixed, so runs are reproducible, and
//   mumps_mem_percent   100: Ipopt's 1000 makes the per-factorisation
//                       allocation dominate the iteration time.
//   mu_strategy         monotone: on random grasps adaptive needs several
//                       times the iterations on EXACT for the same answers.
//   bound_relax_factor  0: rows hold to Ipopt's tolerance (the default 1e-8
//                       relaxes a bound in proportion to its size, so a 40 N
//                       bound is missed by about 4e-7 N and plans drift from
//                       the geometric backend's), and the cone slacks stay
//                       strictly positive.
//   hessian_constant, jac_d_constant   yes for PYRAMID (a convex QP: nothing
//                       is re-evaluated); jac_c_constant yes always (the
//                       equalities are linear in both models).
//
// Time limit: options.ipopt.max_cpu_seconds > 0 is a budget on the CPU time
// of the calling thread (CLOCK_THREAD_CPUTIME_ID) for the whole solve,
// checked after every Ipopt iteration. Ipopt's own max_cpu_time is not used:
// Ipopt 3.11 measures it with getrusage(RUSAGE_SELF), the CPU time of the
// whole process, so with concurrent solves in the server it would stop them
// far too early. (Ipopt, sequential MUMPS and the reference BLAS run in the
// calling thread, so its clock sees all of the work.) control.interrupt is
// polled at the same points and while waiting for the MUMPS lock.
//
// Thread safety: every solve has its own IpoptApplication, NLP and data.
// The one shared object is a process-wide mutex around each Ipopt run,
// because Debian's sequential MUMPS is not thread-safe (see MumpsMutex()):
// Ipopt runs are serialised across threads.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <memory>
#include <mutex>
#include <string>
#include <utility>

#include <Eigen/Core>

#include "IpIpoptApplication.hpp"
#include "IpSolveStatistics.hpp"
#include "planner/src/backends.h"
#include "planner/src/ipopt_formulation.h"
#include "planner/src/ipopt_nlp.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner::internal {
namespace {

using Eigen::VectorXd;

// The phase-one optimum t* (N) proves infeasibility above this times
// max(1, largest bound).
constexpr double kInfeasibilityTolerance = 1e-7;
// Iteration budget of the first minimum-norm run; a run that needs more goes
// through the phase-one problem and a second run with the full budget.
constexpr int kFirstRunIterations = 300;
// Whether the first run uses Ipopt's expect_infeasible_problem heuristic.
constexpr bool kExpectInfeasibleFirst = true;

const char* StatusName(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded:
      return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level:
      return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected:
      return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small:
      return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates:
      return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop:
      return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found:
      return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded:
      return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed:
      return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation:
      return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded:
      return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom:
      return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition:
      return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option:
      return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected:
      return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception:
      return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown:
      return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory:
      return "Insufficient_Memory";
    case Ipopt::Internal_Error:
      return "Internal_Error";
  }
  return "Unknown_Ipopt_Status";
}

PlanResult Infeasible(std::string message) {
  PlanResult result;
  result.status = PlanStatus::kInfeasible;
  result.message = std::move(message);
  return result;
}

PlanResult Failure(std::string message) {
  PlanResult result;
  result.status = PlanStatus::kSolverFailure;
  result.message = std::move(message);
  return result;
}

// The equilibrium rows determine the forces completely: the unique
// equilibrium is the answer if it meets every constraint.
PlanResult CheckUniqueEquilibrium(const Formulation& form, const PreparedProblem& prepared) {
  const double* z = form.start.data();
  const VectorXd values = form.LinearValues(z);
  for (int r = form.num_equilibrium; r < form.num_linear; ++r) {
    if (form.origin[r].kind != RowOrigin::kPlanRow) continue;
    if (values(r) >
        form.upper[r] + kFeasibilityTolerance * std::max(1.0, std::abs(form.upper[r]))) {
      return Infeasible("the equilibrium forces are unique and violate " +
                        prepared.rows.Describe(form.origin[r].index, prepared.problem));
    }
  }
  for (const ConeConstraint& cone : form.cones) {
    if (cone.Tangential(z).norm() >
        cone.Radius(z) + kFeasibilityTolerance * std::max(1.0, cone.Force(z).norm())) {
      return Infeasible(
          "the equilibrium forces are unique and violate the "
          "friction cone of " +
          ContactLabel(prepared.problem, cone.contact));
    }
  }
  PlanResult result;
  result.status = PlanStatus::kOptimal;
  result.forces = form.Forces(form.start.head(form.num_forces));
  return result;
}

// Appends `name` to the comma-separated `rejected` unless `accepted`.
void NoteRejected(bool accepted, const char* name, std::string* rejected) {
  if (!accepted) *rejected += rejected->empty() ? name : std::string(", ") + name;
}

// Sets every option explicitly; returns the names of rejected ones.
std::string ConfigureIpopt(Ipopt::IpoptApplication& app, const PlanOptions& options, int max_iter,
                           bool has_cones, bool expect_infeasible) {
  Ipopt::OptionsList& o = *app.Options();
  std::string r;
  NoteRejected(o.SetIntegerValue("print_level", 0), "print_level", &r);
  NoteRejected(o.SetStringValue("sb", "yes"), "sb", &r);
  NoteRejected(o.SetNumericValue("tol", options.ipopt.tolerance), "tol", &r);
  NoteRejected(o.SetIntegerValue("max_iter", max_iter), "max_iter", &r);
  NoteRejected(o.SetStringValue("mu_strategy", "monotone"), "mu_strategy", &r);
  NoteRejected(o.SetStringValue("linear_solver", "mumps"), "linear_solver", &r);
  NoteRejected(o.SetIntegerValue("mumps_pivot_order", 0), "mumps_pivot_order", &r);
  // MUMPS workspace: 100% above its estimate instead of Ipopt's 1000%; the
  // allocation per factorisation dominates the run time of these tiny
  // systems (Ipopt doubles it and refactorises if MUMPS ever asks for more).
  NoteRejected(o.SetIntegerValue("mumps_mem_percent", 100), "mumps_mem_percent", &r);
  NoteRejected(o.SetStringValue("jac_c_constant", "yes"), "jac_c_constant", &r);
  if (!has_cones) {
    NoteRejected(o.SetStringValue("jac_d_constant", "yes"), "jac_d_constant", &r);
    NoteRejected(o.SetStringValue("hessian_constant", "yes"), "hessian_constant", &r);
  }
  // No relaxation of the bounds: the rows hold to Ipopt's tolerance (the
  // default 1e-8 relative relaxation let plans violate a 40 N bound by
  // 4e-7 N and differ from the geometric backend by up to 5e-6 N), and the
  // cone slacks s stay strictly positive (r divides by them).
  NoteRejected(o.SetNumericValue("bound_relax_factor", 0.0), "bound_relax_factor", &r);
  NoteRejected(o.SetStringValue("expect_infeasible_problem", expect_infeasible ? "yes" : "no"),
               "expect_infeasible_problem", &r);
  return r;
}

// The outcome of one Ipopt run.
struct IpoptRun {
  Ipopt::ApplicationReturnStatus status = Ipopt::Internal_Error;
  std::string setup_error;  // non-empty: Ipopt did not run
  int iterations = 0;
  StopConditions::Reason stopped = StopConditions::kNone;
  double last_mu = 0.0;  // barrier parameter of the last iteration
  bool stalled = false;  // stopped by the stall test (User_Requested_Stop)
  bool stalled_in_restoration = false;
  VectorXd solution;

  bool succeeded() const {
    return setup_error.empty() && stopped == StopConditions::kNone &&
           (status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level) &&
           solution.size() > 0 && solution.allFinite();
  }
};

// Debian's sequential MUMPS (libdmumps_seq 5.5) keeps Fortran module state
// and is not thread-safe: two Ipopt runs at once abort the process
// ("PB allocation in DMUMPS_LOAD_INIT ... MPI_ABORT"). Each IpoptApplication
// therefore lives, from construction to destruction (MUMPS is set up and
// torn down with it), under this process-wide lock. Only the Ipopt runs are
// serialised; everything else in a solve runs concurrently.
std::timed_mutex& MumpsMutex() {
  static std::timed_mutex mutex;
  return mutex;
}

// One Ipopt run; the caller holds MumpsMutex(). Everything Ipopt allocated
// is released before this returns.
IpoptRun RunIpoptLocked(const Formulation& form, Phase phase, VectorXd start, int max_iter,
                        bool expect_infeasible, const PlanOptions& options,
                        const StopConditions& stop) {
  IpoptRun run;
  Ipopt::SmartPtr<ForceNlp> nlp = new ForceNlp(form, phase, std::move(start), stop);
  // No console journal: nothing is ever written to stdout.
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app =
      new Ipopt::IpoptApplication(/*create_console_out=*/false);
  const std::string rejected =
      ConfigureIpopt(*app, options, max_iter, !form.cones.empty(), expect_infeasible);
  if (!rejected.empty()) {
    run.setup_error = "Ipopt rejected the options: " + rejected;
    return run;
  }
  // "" = do not read an ipopt.opt file from the working directory.
  run.status = app->Initialize(std::string());
  if (run.status != Ipopt::Solve_Succeeded) {
    run.setup_error = std::string("Ipopt failed to initialise: ") + StatusName(run.status);
    return run;
  }
  run.status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
  run.iterations = nlp->last_iteration();
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics(); Ipopt::IsValid(stats)) {
    run.iterations = stats->IterationCount();
  }
  run.stopped = nlp->stop_reason();
  run.last_mu = nlp->last_mu();
  run.stalled = nlp->stalled();
  run.stalled_in_restoration = nlp->stalled_in_restoration();
  if (run.status == Ipopt::Maximum_CpuTime_Exceeded) {
    run.stopped = StopConditions::kTimeLimit;  // max_cpu_time is not set
  }
  run.solution = nlp->solution();
  return run;
}

IpoptRun RunIpopt(const Formulation& form, Phase phase, VectorXd start, int max_iter,
                  bool expect_infeasible, const PlanOptions& options, const StopConditions& stop) {
  // Wait for the lock, still honouring an interrupt (the CPU budget does not
  // run down while blocked).
  std::unique_lock<std::timed_mutex> lock(MumpsMutex(), std::defer_lock);
  do {
    if (const StopConditions::Reason reason = stop.Check(); reason != StopConditions::kNone) {
      IpoptRun run;
      run.stopped = reason;
      return run;
    }
  } while (!lock.try_lock_for(std::chrono::milliseconds(2)));
  return RunIpoptLocked(form, phase, std::move(start), max_iter, expect_infeasible, options, stop);
}

// The Ipopt runs of one solve (steps 1-3 of the file comment), counting the
// iterations they use; every result it returns carries that count.
class IpoptSession {
 public:
  IpoptSession(const Formulation& form, const PlanOptions& options, const StopConditions& stop)
      : form_(form), options_(options), stop_(stop) {}

  // 1. The minimum-norm problem, with Ipopt's quick infeasibility heuristic.
  PlanResult Solve() {
    const IpoptRun first =
        Run(Phase::kMinimumNorm, form_.start,
            std::min(options_.ipopt.max_iterations, kFirstRunIterations), kExpectInfeasibleFirst);
    if (first.stopped != StopConditions::kNone) return Stopped(first.stopped);
    if (Converged(first, Phase::kMinimumNorm)) return Optimal(first);
    if (!first.setup_error.empty()) return Failed(first);
    if (first.status == Ipopt::Infeasible_Problem_Detected) return DetectedInfeasible(first);
    return DecideFeasibility(first);
  }

 private:
  // One Ipopt run; adds its iterations to the count and notes its status.
  IpoptRun Run(Phase phase, VectorXd start, int max_iter, bool expect_infeasible) {
    IpoptRun run =
        RunIpopt(form_, phase, std::move(start), max_iter, expect_infeasible, options_, stop_);
    iterations_ += run.iterations;
    ++runs_;
    last_status_ = run.status;
    return run;
  }

  // Every constraint is convex (r = |P f|^2 / s - s is a perspective), so
  // the point of locally least violation Ipopt converged to is a global one.
  PlanResult DetectedInfeasible(const IpoptRun& first) const {
    std::string message = "Ipopt: Infeasible_Problem_Detected";
    if (first.solution.size() == form_.num_vars()) {
      message += " (its point of least violation misses a constraint by " +
                 FormatNumber(form_.MaxViolation(first.solution)) + " N)";
    }
    return Finish(Infeasible(message));
  }

  // 2. Decide feasibility with the phase-one problem; 3. if feasible, solve
  //    again from a feasible point with the heuristic off.
  PlanResult DecideFeasibility(const IpoptRun& first) {
    const IpoptRun phase1 = Run(Phase::kFeasibility, PhaseOneStart(), options_.ipopt.max_iterations,
                                /*expect_infeasible=*/false);
    if (phase1.stopped != StopConditions::kNone) return Stopped(phase1.stopped);
    if (!Converged(phase1, Phase::kFeasibility)) {
      return Finish(Failure(std::string("Ipopt failed: ") + StatusName(first.status) +
                            ", and the feasibility problem ended with " +
                            StatusName(phase1.status) + " after " + std::to_string(iterations_) +
                            " iterations"));
    }
    VectorXd x1 = phase1.solution.head(form_.num_vars());
    const double violation = form_.MaxViolation(x1);
    if (violation > kInfeasibilityTolerance * form_.scale) {
      return Finish(Infeasible(std::string("Ipopt: ") + StatusName(first.status) +
                               "; no equilibrium meets the tightened constraints (the least "
                               "violation found is " +
                               FormatNumber(violation) + " N)"));
    }
    const IpoptRun retry = Run(Phase::kMinimumNorm, RetryStart(std::move(x1)),
                               options_.ipopt.max_iterations, /*expect_infeasible=*/false);
    if (retry.stopped != StopConditions::kNone) return Stopped(retry.stopped);
    if (Converged(retry, Phase::kMinimumNorm)) return Optimal(retry);
    return Failed(retry);
  }

  // The minimum-norm equilibrium with t above every violation.
  VectorXd PhaseOneStart() const {
    const int nv = form_.num_vars();
    VectorXd start(nv + 1);
    start.head(nv) = form_.start;
    const double t0 = std::max(0.0, form_.MaxViolation(form_.start)) + 1e-2 * form_.scale;
    start(nv) = t0;
    for (const ConeConstraint& cone : form_.cones) {
      start(cone.s_index) = cone.Radius(form_.start.data()) + t0;
    }
    return start;
  }

  // From the feasible phase-one point x1, the feasible point closest to the
  // minimum-norm equilibrium on the segment between the two (phase one
  // leaves internal forces arbitrarily large). Both ends satisfy the
  // equilibrium; the constraints are convex, so the feasible part of the
  // segment is an interval found by bisection. Slacks reset inside r's domain.
  VectorXd RetryStart(VectorXd x1) const {
    const VectorXd direction = form_.start - x1;
    double feasible = 0.0, infeasible = 1.0;
    const double tol = kFeasibilityTolerance * form_.scale;
    if (form_.MaxViolation(x1 + direction) <= tol) {
      feasible = 1.0;
    } else {
      for (int k = 0; k < 40; ++k) {
        const double mid = 0.5 * (feasible + infeasible);
        (form_.MaxViolation(x1 + mid * direction) <= tol ? feasible : infeasible) = mid;
      }
    }
    x1 += 0.99 * feasible * direction;
    for (const ConeConstraint& cone : form_.cones) {
      x1(cone.s_index) =
          std::max({cone.Radius(x1.data()), cone.Tangential(x1.data()).norm(), 1e-6 * form_.scale});
    }
    return x1;
  }

  // Solve_Succeeded / Solved_To_Acceptable_Level; or a run that stalled
  // (Search_Direction_Becomes_Too_Small, or ForceNlp's stall test) with the
  // barrier parameter at its final value and forces that meet every
  // constraint: a contact at a cone apex (feasible, optimality not certified).
  bool Converged(const IpoptRun& run, Phase phase) const {
    if (run.succeeded()) return true;
    const bool stalled =
        run.status == Ipopt::Search_Direction_Becomes_Too_Small ||
        (run.status == Ipopt::User_Requested_Stop && run.stalled && !run.stalled_in_restoration);
    if (!run.setup_error.empty() || run.stopped != StopConditions::kNone || !stalled ||
        run.solution.size() == 0 || !run.solution.allFinite()) {
      return false;
    }
    const double tol = kFeasibilityTolerance * form_.scale;
    return run.last_mu <= 10.0 * options_.ipopt.tolerance &&
           form_.EquilibriumResidual(run.solution) <= tol &&
           (phase == Phase::kFeasibility || form_.MaxViolation(run.solution) <= tol);
  }

  PlanResult Optimal(const IpoptRun& run) const {
    PlanResult result;
    result.status = PlanStatus::kOptimal;
    if (run.status == Ipopt::Solved_To_Acceptable_Level) {
      result.message = "Ipopt: Solved_To_Acceptable_Level";
    } else if (run.status != Ipopt::Solve_Succeeded) {
      result.message =
          "Ipopt stalled at a cone apex (degenerate multipliers) with the barrier parameter at "
          "its final value; accepted: the forces meet every constraint, optimality not "
          "certified";
    }
    result.forces = form_.Forces(run.solution.head(form_.num_forces));
    return Finish(result);
  }

  PlanResult Stopped(StopConditions::Reason reason) const {
    const std::string after = " after " + std::to_string(iterations_) + " Ipopt iterations";
    if (reason == StopConditions::kInterrupted) return Finish(Failure("interrupted" + after));
    return Finish(Failure("Ipopt stopped at the time limit (" +
                          FormatNumber(options_.ipopt.max_cpu_seconds) + " s CPU)" + after));
  }

  PlanResult Failed(const IpoptRun& run) const {
    if (!run.setup_error.empty()) return Finish(Failure(run.setup_error));
    return Finish(Failure(std::string("Ipopt failed: ") + StatusName(run.status) + " after " +
                          std::to_string(iterations_) + " iterations"));
  }

  PlanResult Finish(PlanResult result) const {
    result.iterations = iterations_;
    result.ipopt.runs = runs_;
    if (runs_ > 0) {
      result.ipopt.status = static_cast<int>(last_status_);
      result.ipopt.status_name = StatusName(last_status_);
    }
    return result;
  }

  const Formulation& form_;
  const PlanOptions& options_;
  const StopConditions& stop_;
  int iterations_ = 0;
  int runs_ = 0;
  Ipopt::ApplicationReturnStatus last_status_ = Ipopt::Solve_Succeeded;
};

PlanResult SolveOrThrow(const PreparedProblem& prepared, const PlanOptions& options,
                        const SolveControl& control) {
  const StopConditions stop{options.ipopt.max_cpu_seconds, ThreadCpuSeconds(), &control.interrupt};
  const ForceEquilibrium& eq = prepared.equilibrium;
  if (!eq.consistent) {
    return Infeasible("the contacts cannot resist this wrench (rank " + std::to_string(eq.rank) +
                      " of G, residual " + FormatNumber(eq.residual) + ")");
  }
  const FormulationOutcome built = BuildFormulation(prepared, options);
  if (!built.infeasible.empty()) return Infeasible(built.infeasible);
  if (built.form.num_equilibrium >= built.form.num_forces) {
    return CheckUniqueEquilibrium(built.form, prepared);
  }
  return IpoptSession(built.form, options, stop).Solve();
}

class IpoptSolver final : public ForceSolver {
 public:
  IpoptSolver() : ForceSolver(SolverKind::kIpopt) {}

 protected:
  void DoSolve(const PlanOptions& options, const SolveControl& control,
               PlanningWorkspace* workspace, PlanResult* result) const override {
    *result = Run(workspace->prepared, options, control);
  }

 private:
  static PlanResult Run(const PreparedProblem& prepared, const PlanOptions& options,
                        const SolveControl& control) {
    try {
      return SolveOrThrow(prepared, options, control);
    } catch (const Ipopt::IpoptException& e) {
      return Failure("Ipopt raised " + e.Message());
    } catch (const std::exception& e) {
      return Failure(std::string("Ipopt backend error: ") + e.what());
    } catch (...) {
      return Failure("Ipopt backend error: unknown exception");
    }
  }
};

}  // namespace

std::unique_ptr<ForceSolver> MakeIpoptSolver() { return std::make_unique<IpoptSolver>(); }

}  // namespace tactforce::planner::internal
