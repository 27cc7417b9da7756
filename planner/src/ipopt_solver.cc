// Ipopt reference backend (SolverKind::kIpopt).
//
// Solves the force-planning problem directly with a general interior-point
// NLP solver (Ipopt 3.11, MUMPS), as an independent check of the geometric
// backend:
//
//   minimise   sum_i |f_i|^2                              (f in R^{3n})
//   subject to U_r^T G f = U_r^T b         (independent equilibrium rows)
//              A f <= d                    (robustly tightened linear rows)
//   EXACT, per contact i with mu_i > 0 (P = I - n_i n_i^T):
//              |P f_i| + kappa rho_t,i <= mu_i (n_i . f_i - kappa rho_n,i)
//
// EXACT cone formulation. Each contact with friction gets a slack unknown
//   s_i = mu_i (n_i . f_i - kappa rho_n,i) - kappa rho_t,i   (linear row),
// bounded by s_i >= 0, and the convex constraint
//   r_i(f, s) = |P f_i|^2 / s_i - s_i <= 0          (i.e. |P f_i| <= s_i)
// with exact gradients and Hessians. Why not |P f|^2 - s^2 <= 0 with a
// linear row s >= 0: its gradient vanishes at the cone apex, which is where
// the minimum-norm plan puts every contact it does not need; there Ipopt
// took ~850 iterations and left 1e-4 N of tangential force on a contact that
// should carry none (a violation eps of the squared form admits sqrt(eps)
// of force). A smoothed sqrt(|P f|^2 + eps^2) - eps <= s behaves like |P f|
// for small eps and made Ipopt oscillate (400+ iterations at eps = 1e-4 N).
// r keeps a non-zero gradient (dr/ds <= -1) and measures violations in N.
// Its one weakness: at an apex (s = 0, P f = 0) the bound s >= 0 and r are
// both active with parallel gradients, so the multipliers are not unique.
// Ipopt then sometimes keeps iterating with a vanishing primal step and a
// dual infeasibility that cannot reach tol; such a run is stopped after
// kStallIterations and accepted only if the barrier parameter is at its
// final value and the forces meet every constraint (checked here; the
// message says so). Those plans are feasible but their optimality is not
// certified: on random grasps they were within ~1e-4 N of the optimum.
//
// Frictionless contacts (mu_i == 0) have a cone with no interior (a ray):
// their force is parametrised as f_i = n_i z_i, for both cone models. The
// equilibrium rows are then re-reduced to full row rank in the reduced
// unknowns, and friction facets of such a contact become bound checks.
// When the equilibrium leaves no freedom at all (e.g. a single contact) the
// unique equilibrium is checked directly, without Ipopt.
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
//   tol                 options.ipopt_tolerance (scaled overall NLP error)
//   max_iter            options.ipopt_max_iterations per run (the first
//                       run: at most kFirstRunIterations)
//   print_level 0, sb yes, and no console journal: Ipopt never prints.
//   linear_solver       mumps (the only one in Debian's build), with
//   mumps_pivot_order   0 (AMD): fixed, so runs are reproducible, and
//   mumps_mem_percent   100: Ipopt's 1000 made the per-factorisation
//                       allocation dominate (1.0 -> 0.53 ms per iteration).
//   mu_strategy         monotone: on 600 random grasps adaptive needed 3.5x
//                       the iterations on EXACT (max 2489) for the same
//                       answers; monotone 24 on average, at most 317.
//   bound_relax_factor  0: rows hold to Ipopt's tolerance (with the default
//                       1e-8 a 40 N bound was missed by 4e-7 N and plans
//                       differed from the geometric backend by 5e-6 N; now
//                       1.2e-7 N over the 2,000-grasp property test), and
//                       the cone slacks stay strictly positive.
//   hessian_constant, jac_d_constant   yes for PYRAMID (a convex QP: nothing
//                       is re-evaluated); jac_c_constant yes always (the
//                       equalities are linear in both models).
//
// Time limit: options.ipopt_max_cpu_seconds > 0 is a budget on the CPU time
// of the calling thread (CLOCK_THREAD_CPUTIME_ID) for the whole solve,
// checked after every Ipopt iteration. Ipopt's own max_cpu_time is not used:
// Ipopt 3.11 measures it with getrusage(RUSAGE_SELF), the CPU time of the
// whole process, so with concurrent solves in the server it would stop them
// far too early. (Ipopt, sequential MUMPS and the reference BLAS run in the
// calling thread, so its clock sees all of the work.) options.interrupt is
// polled at the same points and while waiting for the MUMPS lock.
//
// Thread safety: every solve has its own IpoptApplication, NLP and data.
// The one shared object is a process-wide mutex around each Ipopt run,
// because Debian's sequential MUMPS is not thread-safe (see MumpsMutex()):
// Ipopt runs are serialised across threads.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/SVD>

#include "IpIpoptApplication.hpp"
#include "IpSolveStatistics.hpp"
#include "IpTNLP.hpp"
#include "backends.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner::internal {
namespace {

using Ipopt::Index;
using Ipopt::Number;

// Any bound beyond Ipopt's nlp_{lower,upper}_bound_inf (1e19) is infinite.
constexpr double kInfinity = 1e20;
// Absolute slack (N) for the checks made without Ipopt (facets of
// frictionless contacts, uniquely determined equilibria): rho_t and the row
// tightening take square roots, so round-off can reach ~1e-9 N.
constexpr double kFeasibilityTolerance = 1e-8;
// Relative residual accepted for the re-reduced equilibrium rows (the same
// test ComputeForceEquilibrium applies to G f = b).
constexpr double kEquilibriumTolerance = 1e-8;
// The phase-one optimum t* (N) proves infeasibility above this times
// max(1, largest bound).
constexpr double kInfeasibilityTolerance = 1e-7;
// A run has stalled when the primal step stays below kStallStep times the
// size of the unknowns for kStallIterations iterations.
constexpr double kStallStep = 1e-12;
constexpr int kStallIterations = 8;
// Iteration budget of the first minimum-norm run; a run that needs more goes
// through the phase-one problem and a second run with the full budget.
constexpr int kFirstRunIterations = 300;
// Whether the first run uses Ipopt's expect_infeasible_problem heuristic.
constexpr bool kExpectInfeasibleFirst = true;

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

std::string FormatNumber(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

std::string ContactLabel(const PlanProblem& problem, int contact) {
  std::string label = "contact " + std::to_string(contact);
  const std::string& name = problem.contacts[static_cast<size_t>(contact)].name;
  if (!name.empty()) label += " (" + name + ")";
  return label;
}

const char* StatusName(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded: return "Solve_Succeeded";
    case Ipopt::Solved_To_Acceptable_Level: return "Solved_To_Acceptable_Level";
    case Ipopt::Infeasible_Problem_Detected: return "Infeasible_Problem_Detected";
    case Ipopt::Search_Direction_Becomes_Too_Small:
      return "Search_Direction_Becomes_Too_Small";
    case Ipopt::Diverging_Iterates: return "Diverging_Iterates";
    case Ipopt::User_Requested_Stop: return "User_Requested_Stop";
    case Ipopt::Feasible_Point_Found: return "Feasible_Point_Found";
    case Ipopt::Maximum_Iterations_Exceeded: return "Maximum_Iterations_Exceeded";
    case Ipopt::Restoration_Failed: return "Restoration_Failed";
    case Ipopt::Error_In_Step_Computation: return "Error_In_Step_Computation";
    case Ipopt::Maximum_CpuTime_Exceeded: return "Maximum_CpuTime_Exceeded";
    case Ipopt::Not_Enough_Degrees_Of_Freedom: return "Not_Enough_Degrees_Of_Freedom";
    case Ipopt::Invalid_Problem_Definition: return "Invalid_Problem_Definition";
    case Ipopt::Invalid_Option: return "Invalid_Option";
    case Ipopt::Invalid_Number_Detected: return "Invalid_Number_Detected";
    case Ipopt::Unrecoverable_Exception: return "Unrecoverable_Exception";
    case Ipopt::NonIpopt_Exception_Thrown: return "NonIpopt_Exception_Thrown";
    case Ipopt::Insufficient_Memory: return "Insufficient_Memory";
    case Ipopt::Internal_Error: return "Internal_Error";
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

// One entry of a sparse matrix.
struct Entry {
  int row = 0;
  int col = 0;
  double value = 0.0;
};

// The exact cone of one contact with friction: |P f| <= s with the slack
// unknown s = mu n.f - shift >= 0 (shift = kappa (mu rho_n + rho_t)), posed
// as r(f, s) = |P f|^2 / s - s <= 0.
struct ConeConstraint {
  int contact = 0;
  int offset = 0;   // first of the contact's three force unknowns
  int s_index = 0;  // the slack unknown s
  Vec3 normal = Vec3::UnitZ();
  double mu = 0.0;
  double shift = 0.0;

  Vec3 Force(const Number* x) const {
    return Vec3(x[offset], x[offset + 1], x[offset + 2]);
  }
  Vec3 Tangential(const Number* x) const {
    const Vec3 f = Force(x);
    return f - normal.dot(f) * normal;
  }
  // s(f): the cone radius available at the forces in x.
  double Radius(const Number* x) const {
    return mu * normal.dot(Force(x)) - shift;
  }
  // |P f| - s(f): > 0 outside the cone (N).
  double Violation(const Number* x) const {
    return Tangential(x).norm() - Radius(x);
  }
  double Value(const Number* x) const {
    const double s = x[s_index];
    return Tangential(x).squaredNorm() / s - s;
  }
};

// Where a linear row came from.
struct RowOrigin {
  enum Kind { kEquilibrium, kPlanRow, kConeSlack } kind = kEquilibrium;
  int index = 0;  // row of prepared.rows, or contact
};

// The NLP. Unknowns x = (z, s): z are the reduced forces, f_i = z_i (3
// unknowns) for contacts with friction and f_i = n_i z_i (1 unknown) for
// frictionless ones (orthonormal map, so |f|^2 = |z|^2); s are the cone
// slacks (EXACT only).
struct Formulation {
  int num_forces = 0;  // unknowns in z
  std::vector<int> offset;         // per contact
  std::vector<bool> frictionless;  // per contact
  std::vector<Vec3> normal;        // per contact
  // Linear constraints lower <= L z <= upper; the equilibrium rows first.
  int num_equilibrium = 0;
  int num_linear = 0;
  std::vector<Entry> linear;
  std::vector<double> lower;
  std::vector<double> upper;
  std::vector<RowOrigin> origin;
  std::vector<ConeConstraint> cones;  // constraints num_linear, ...
  VectorXd start;      // (z0, s0): the minimum-norm equilibrium
  double scale = 1.0;  // max(1, largest finite bound), N

  int num_vars() const { return num_forces + static_cast<int>(cones.size()); }
  int num_constraints() const {
    return num_linear + static_cast<int>(cones.size());
  }

  std::vector<Vec3> Forces(const VectorXd& z) const {
    std::vector<Vec3> forces(offset.size());
    for (size_t i = 0; i < offset.size(); ++i) {
      forces[i] = frictionless[i] ? Vec3(normal[i] * z(offset[i]))
                                  : Vec3(z.segment<3>(offset[i]));
    }
    return forces;
  }

  VectorXd LinearValues(const Number* z) const {
    VectorXd values = VectorXd::Zero(num_linear);
    for (const Entry& e : linear) values(e.row) += e.value * z[e.col];
    return values;
  }

  // Largest violation (N) of the plan rows and exact cones at the forces in
  // x (the slacks in x are ignored).
  double MaxViolation(const VectorXd& x) const {
    const VectorXd values = LinearValues(x.data());
    double violation = 0.0;
    for (int r = 0; r < num_linear; ++r) {
      if (origin[r].kind == RowOrigin::kPlanRow) {
        violation = std::max(violation, values(r) - upper[r]);
      }
    }
    for (const ConeConstraint& cone : cones) {
      violation = std::max(violation, cone.Violation(x.data()));
    }
    return violation;
  }
  // Largest residual of the equilibrium rows at x.
  double EquilibriumResidual(const VectorXd& x) const {
    const VectorXd values = LinearValues(x.data());
    double residual = 0.0;
    for (int r = 0; r < num_equilibrium; ++r) {
      residual = std::max(residual, std::abs(values(r) - upper[r]));
    }
    return residual;
  }
};

// Either a formulation to solve, or an answer found while building it.
struct BuildOutcome {
  bool decided = false;
  PlanResult result;
};

BuildOutcome BuildFormulation(const PreparedProblem& prepared,
                              const PlanOptions& options, Formulation* form) {
  const PlanProblem& problem = prepared.problem;
  const ForceEquilibrium& eq = prepared.equilibrium;
  const int n = prepared.num_contacts();
  const double kappa = options.confidence;

  // Unknowns.
  form->offset.resize(static_cast<size_t>(n));
  form->frictionless.resize(static_cast<size_t>(n));
  form->normal.resize(static_cast<size_t>(n));
  bool reduced = false;
  int num_forces = 0;
  for (int i = 0; i < n; ++i) {
    const Contact& c = problem.contacts[static_cast<size_t>(i)];
    form->offset[i] = num_forces;
    form->frictionless[i] = c.friction == 0.0;
    form->normal[i] = c.normal;
    num_forces += form->frictionless[i] ? 1 : 3;
    reduced = reduced || form->frictionless[i];
  }
  form->num_forces = num_forces;

  // T: f = T z (3n x num_forces), only needed when some contact is reduced.
  MatrixXd map;
  if (reduced) {
    map = MatrixXd::Zero(3 * n, num_forces);
    for (int i = 0; i < n; ++i) {
      if (form->frictionless[i]) {
        map.block<3, 1>(3 * i, form->offset[i]) = form->normal[i];
      } else {
        map.block<3, 3>(3 * i, form->offset[i]).setIdentity();
      }
    }
  }

  // Equilibrium rows of full row rank in z, and the minimum-norm solution.
  MatrixXd eq_rows;
  VectorXd eq_rhs;
  VectorXd z0;
  if (!reduced) {
    eq_rows = eq.independent_rows;
    eq_rhs = eq.independent_rhs;
    z0 = eq.particular;
  } else {
    const MatrixXd e = eq.independent_rows * map;
    const VectorXd& b = eq.independent_rhs;
    Eigen::JacobiSVD<MatrixXd> svd(e, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const VectorXd& sv = svd.singularValues();
    const double cutoff =
        sv.size() > 0 ? options.rank_tolerance * std::max(1.0, sv(0)) : 0.0;
    int rank = 0;
    while (rank < sv.size() && sv(rank) > cutoff) ++rank;
    const MatrixXd u = svd.matrixU().leftCols(rank);
    eq_rhs = u.transpose() * b;
    eq_rows = u.transpose() * e;
    z0 = svd.matrixV().leftCols(rank) *
         (eq_rhs.array() / sv.head(rank).array()).matrix();
    const double residual = (e * z0 - b).norm();
    if (!(residual <= kEquilibriumTolerance * std::max(1.0, b.norm()))) {
      return {true,
              Infeasible("the contacts cannot resist this wrench with the "
                         "frictionless contacts pushing only along their "
                         "normals (rank " + std::to_string(rank) +
                         " in the remaining unknowns, residual " +
                         FormatNumber(residual) + ")")};
    }
  }

  auto add_row = [&](const std::vector<std::pair<int, double>>& terms,
                     double lo, double hi, RowOrigin origin) {
    const int r = static_cast<int>(form->lower.size());
    for (const auto& [col, value] : terms) {
      if (value != 0.0) form->linear.push_back({r, col, value});
    }
    form->lower.push_back(lo);
    form->upper.push_back(hi);
    form->origin.push_back(origin);
    if (std::abs(lo) < kInfinity) form->scale = std::max(form->scale, std::abs(lo));
    if (std::abs(hi) < kInfinity) form->scale = std::max(form->scale, std::abs(hi));
  };

  auto dense = [](const Eigen::RowVectorXd& row) {
    std::vector<std::pair<int, double>> terms;
    for (int j = 0; j < row.size(); ++j) terms.emplace_back(j, row(j));
    return terms;
  };
  for (int k = 0; k < eq_rows.rows(); ++k) {
    add_row(dense(eq_rows.row(k)), eq_rhs(k), eq_rhs(k),
            {RowOrigin::kEquilibrium, k});
  }
  form->num_equilibrium = static_cast<int>(eq_rows.rows());

  // Tightened linear rows A f <= d.
  const ConstraintRows& rows = prepared.rows;
  for (int k = 0; k < rows.matrix.rows(); ++k) {
    Eigen::RowVectorXd a = rows.matrix.row(k);
    if (reduced) a = a * map;
    const double size = rows.matrix.row(k).cwiseAbs().maxCoeff();
    if (a.cwiseAbs().maxCoeff() <= 1e-12 * size) {
      // Independent of the unknowns left (a friction facet of a frictionless
      // contact): 0 <= d must hold by itself.
      if (rows.rhs(k) < -kFeasibilityTolerance *
                            std::max(1.0, std::abs(rows.nominal_rhs(k)))) {
        return {true, Infeasible(rows.Describe(k, problem) +
                                 " cannot be met: its robust bound is " +
                                 FormatNumber(rows.rhs(k)) + " N")};
      }
      continue;
    }
    add_row(dense(a), -kInfinity, rows.rhs(k), {RowOrigin::kPlanRow, k});
  }

  // Exact friction cones: s_i - mu n.f_i = -shift, s_i >= 0, r_i <= 0.
  if (options.cone == ConeModel::kExact) {
    for (int i = 0; i < n; ++i) {
      const Contact& c = problem.contacts[static_cast<size_t>(i)];
      const double rho_n = prepared.normal_sigma[static_cast<size_t>(i)];
      const double rho_t = prepared.tangential_sigma[static_cast<size_t>(i)];
      if (form->frictionless[i]) {
        // |P f| + kappa rho_t <= 0 with P f = 0: only the uncertainty is left.
        if (kappa * rho_t > kFeasibilityTolerance) {
          return {true,
                  Infeasible(ContactLabel(problem, i) +
                             " is frictionless but must resist a tangential "
                             "force uncertainty kappa*rho_t = " +
                             FormatNumber(kappa * rho_t) + " N")};
        }
        continue;
      }
      ConeConstraint cone;
      cone.contact = i;
      cone.offset = form->offset[i];
      cone.s_index = num_forces + static_cast<int>(form->cones.size());
      cone.normal = c.normal;
      cone.mu = c.friction;
      cone.shift = kappa * (c.friction * rho_n + rho_t);
      std::vector<std::pair<int, double>> terms = {{cone.s_index, 1.0}};
      for (int a = 0; a < 3; ++a) {
        terms.emplace_back(cone.offset + a, -cone.mu * c.normal(a));
      }
      add_row(terms, -cone.shift, -cone.shift, {RowOrigin::kConeSlack, i});
      form->cones.push_back(cone);
    }
  }
  form->num_linear = static_cast<int>(form->lower.size());

  // Start: the minimum-norm equilibrium, each slack at least |P f| so that
  // r <= 0 holds and only linear rows are violated (r = |P f|^2 / s - s
  // explodes for small s).
  form->start = VectorXd::Zero(form->num_vars());
  form->start.head(num_forces) = z0;
  for (const ConeConstraint& cone : form->cones) {
    const Number* x = form->start.data();
    form->start(cone.s_index) =
        std::max({cone.Radius(x), cone.Tangential(x).norm(), 1e-2 * form->scale});
  }
  return {};
}

// The equilibrium rows determine the forces completely: the unique
// equilibrium is the answer if it meets every constraint.
PlanResult CheckUniqueEquilibrium(const Formulation& form,
                                  const PreparedProblem& prepared) {
  const Number* z = form.start.data();
  const VectorXd values = form.LinearValues(z);
  for (int r = form.num_equilibrium; r < form.num_linear; ++r) {
    if (form.origin[r].kind != RowOrigin::kPlanRow) continue;
    if (values(r) > form.upper[r] + kFeasibilityTolerance *
                                        std::max(1.0, std::abs(form.upper[r]))) {
      return Infeasible(
          "the equilibrium forces are unique and violate " +
          prepared.rows.Describe(form.origin[r].index, prepared.problem));
    }
  }
  for (const ConeConstraint& cone : form.cones) {
    if (cone.Tangential(z).norm() >
        cone.Radius(z) +
            kFeasibilityTolerance * std::max(1.0, cone.Force(z).norm())) {
      return Infeasible("the equilibrium forces are unique and violate the "
                        "friction cone of " +
                        ContactLabel(prepared.problem, cone.contact));
    }
  }
  PlanResult result;
  result.status = PlanStatus::kOptimal;
  result.forces = form.Forces(form.start.head(form.num_forces));
  return result;
}

// Why a solve must stop early; shared by the Ipopt runs of one solve.
struct StopConditions {
  double limit_seconds = 0.0;  // CPU budget; <= 0: none
  double start_seconds = 0.0;  // thread CPU clock at the start of the solve
  const std::function<bool()>* interrupt = nullptr;  // options.interrupt

  enum Reason { kNone, kTimeLimit, kInterrupted };
  Reason Check() const {
    if (interrupt != nullptr && *interrupt && (*interrupt)()) return kInterrupted;
    if (limit_seconds > 0.0 &&
        ThreadCpuSeconds() - start_seconds > limit_seconds) {
      return kTimeLimit;
    }
    return kNone;
  }
};

// Which problem the TNLP poses.
enum class Phase {
  // min |f|^2 subject to everything: the answer.
  kMinimumNorm,
  // min t >= 0 with every inequality relaxed by t (rows a.f <= d + t, cone
  // slacks s = s(f) + t); the equilibrium stays exact. Always feasible;
  // t* > 0 proves the problem infeasible.
  kFeasibility,
};

// The TNLP handed to Ipopt. Owned by one run; not shared.
class ForceNlp final : public Ipopt::TNLP {
 public:
  ForceNlp(const Formulation& form, Phase phase, VectorXd start,
           const StopConditions& stop)
      : form_(form),
        phase_(phase),
        start_(std::move(start)),
        stop_(stop),
        t_index_(form.num_vars()),
        num_vars_(form.num_vars() + (phase == Phase::kFeasibility ? 1 : 0)),
        linear_(form.linear),
        stall_step_(kStallStep *
                    std::max({1.0, form.scale, start_.cwiseAbs().maxCoeff()})) {
    if (phase_ == Phase::kFeasibility) {
      for (int r = 0; r < form_.num_linear; ++r) {
        if (form_.origin[r].kind != RowOrigin::kEquilibrium) {
          linear_.push_back({r, t_index_, -1.0});
        }
      }
    }
    // Lower triangle of the Lagrangian Hessian: the diagonal of every force
    // unknown (the objective 2 I); for a cone the 3x3 force block, the (s, f)
    // row and (s, s).
    std::vector<int> cone_of(form_.offset.size(), -1);
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      cone_of[static_cast<size_t>(form_.cones[k].contact)] = static_cast<int>(k);
    }
    cone_hess_start_.resize(form_.cones.size());
    for (size_t i = 0; i < form_.offset.size(); ++i) {
      const int o = form_.offset[i];
      if (form_.frictionless[i]) {
        hess_.push_back({o, o, 0.0});
      } else if (cone_of[i] < 0) {
        for (int a = 0; a < 3; ++a) hess_.push_back({o + a, o + a, 0.0});
      } else {
        cone_hess_start_[static_cast<size_t>(cone_of[i])] =
            static_cast<int>(hess_.size());
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b <= a; ++b) hess_.push_back({o + a, o + b, 0.0});
        }
      }
    }
    for (const ConeConstraint& c : form_.cones) {
      cone_hess_s_start_.push_back(static_cast<int>(hess_.size()));
      for (int a = 0; a < 3; ++a) hess_.push_back({c.s_index, c.offset + a, 0.0});
      hess_.push_back({c.s_index, c.s_index, 0.0});
    }
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override {
    n = num_vars_;
    m = form_.num_constraints();
    nnz_jac_g = static_cast<Index>(linear_.size() + 4 * form_.cones.size());
    nnz_h_lag = static_cast<Index>(hess_.size());
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                       Number* g_u) override {
    for (Index j = 0; j < n; ++j) {
      x_l[j] = j < form_.num_forces ? -kInfinity : 0.0;  // s >= 0, t >= 0
      x_u[j] = kInfinity;
    }
    for (int r = 0; r < form_.num_linear; ++r) {
      g_l[r] = form_.lower[r];
      g_u[r] = form_.upper[r];
    }
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      g_l[form_.num_linear + k] = -kInfinity;
      g_u[form_.num_linear + k] = 0.0;
    }
    return true;
  }

  bool get_constraints_linearity(Index m, LinearityType* types) override {
    for (Index r = 0; r < m; ++r) {
      types[r] = r < form_.num_linear ? LINEAR : NON_LINEAR;
    }
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z,
                          Number* z_L, Number* z_U, Index m, bool init_lambda,
                          Number* lambda) override {
    if (init_z || init_lambda) return false;  // no warm start offered
    if (init_x) {
      for (Index j = 0; j < n; ++j) x[j] = start_(j);
    }
    return true;
  }

  bool eval_f(Index n, const Number* x, bool new_x, Number& obj) override {
    obj = phase_ == Phase::kFeasibility
              ? x[t_index_]
              : Eigen::Map<const VectorXd>(x, form_.num_forces).squaredNorm();
    return true;
  }

  bool eval_grad_f(Index n, const Number* x, bool new_x, Number* grad) override {
    for (Index j = 0; j < n; ++j) {
      if (phase_ == Phase::kFeasibility) {
        grad[j] = j == t_index_ ? 1.0 : 0.0;
      } else {
        grad[j] = j < form_.num_forces ? 2.0 * x[j] : 0.0;
      }
    }
    return true;
  }

  bool eval_g(Index n, const Number* x, bool new_x, Index m, Number* g) override {
    for (Index r = 0; r < m; ++r) g[r] = 0.0;
    for (const Entry& e : linear_) g[e.row] += e.value * x[e.col];
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      if (!(x[form_.cones[k].s_index] > 0.0)) return false;  // outside domain
      g[form_.num_linear + k] = form_.cones[k].Value(x);
    }
    return true;
  }

  bool eval_jac_g(Index n, const Number* x, bool new_x, Index m, Index nele_jac,
                  Index* i_row, Index* j_col, Number* values) override {
    const size_t nl = linear_.size();
    if (values == nullptr) {
      for (size_t e = 0; e < nl; ++e) {
        i_row[e] = linear_[e].row;
        j_col[e] = linear_[e].col;
      }
      for (size_t k = 0; k < form_.cones.size(); ++k) {
        const ConeConstraint& c = form_.cones[k];
        const Index row = form_.num_linear + static_cast<Index>(k);
        for (int a = 0; a < 3; ++a) {
          i_row[nl + 4 * k + a] = row;
          j_col[nl + 4 * k + a] = c.offset + a;
        }
        i_row[nl + 4 * k + 3] = row;
        j_col[nl + 4 * k + 3] = c.s_index;
      }
      return true;
    }
    for (size_t e = 0; e < nl; ++e) values[e] = linear_[e].value;
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      const ConeConstraint& c = form_.cones[k];
      const double s = x[c.s_index];
      if (!(s > 0.0)) return false;
      const Vec3 w = c.Tangential(x);
      // dr/df = 2 P f / s, dr/ds = -|P f|^2 / s^2 - 1.
      for (int a = 0; a < 3; ++a) values[nl + 4 * k + a] = 2.0 * w(a) / s;
      values[nl + 4 * k + 3] = -w.squaredNorm() / (s * s) - 1.0;
    }
    return true;
  }

  bool eval_h(Index n, const Number* x, bool new_x, Number obj_factor, Index m,
              const Number* lambda, bool new_lambda, Index nele_hess,
              Index* i_row, Index* j_col, Number* values) override {
    if (values == nullptr) {
      for (size_t e = 0; e < hess_.size(); ++e) {
        i_row[e] = hess_[e].row;
        j_col[e] = hess_[e].col;
      }
      return true;
    }
    const double diagonal =
        phase_ == Phase::kFeasibility ? 0.0 : 2.0 * obj_factor;
    for (size_t e = 0; e < hess_.size(); ++e) {
      values[e] = hess_[e].row == hess_[e].col && hess_[e].row < form_.num_forces
                      ? diagonal
                      : 0.0;
    }
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      const ConeConstraint& c = form_.cones[k];
      const double s = x[c.s_index];
      if (!(s > 0.0)) return false;
      const double weight = lambda[form_.num_linear + k];
      const Vec3 w = c.Tangential(x);
      // d2r/df2 = 2 P / s, d2r/ds df = -2 P f / s^2, d2r/ds2 = 2 |P f|^2 / s^3.
      const Eigen::Matrix3d p =
          Eigen::Matrix3d::Identity() - c.normal * c.normal.transpose();
      int e = cone_hess_start_[k];
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b <= a; ++b) values[e++] += weight * 2.0 * p(a, b) / s;
      }
      e = cone_hess_s_start_[k];
      for (int a = 0; a < 3; ++a) values[e++] -= weight * 2.0 * w(a) / (s * s);
      values[e] += weight * 2.0 * w.squaredNorm() / (s * s * s);
    }
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn status, Index n, const Number* x,
                         const Number* z_L, const Number* z_U, Index m,
                         const Number* g, const Number* lambda, Number obj_value,
                         const Ipopt::IpoptData* ip_data,
                         Ipopt::IpoptCalculatedQuantities* ip_cq) override {
    solution_ = Eigen::Map<const VectorXd>(x, n);
  }

  bool intermediate_callback(Ipopt::AlgorithmMode mode, Index iter,
                             Number obj_value, Number inf_pr, Number inf_du,
                             Number mu, Number d_norm,
                             Number regularization_size, Number alpha_du,
                             Number alpha_pr, Index ls_trials,
                             const Ipopt::IpoptData* ip_data,
                             Ipopt::IpoptCalculatedQuantities* ip_cq) override {
    last_iteration_ = iter;
    last_mu_ = mu;
    stop_reason_ = stop_.Check();
    if (stop_reason_ != StopConditions::kNone) return false;
    // A stalled run: the primal step has vanished for kStallIterations
    // iterations in a row while Ipopt keeps iterating (degenerate multipliers
    // at a cone apex). Stop; the caller judges the point.
    stall_count_ = iter > 0 && d_norm <= stall_step_ ? stall_count_ + 1 : 0;
    if (stall_count_ >= kStallIterations) {
      stalled_ = true;
      stalled_in_restoration_ = mode == Ipopt::RestorationPhaseMode;
      return false;
    }
    return true;
  }

  const VectorXd& solution() const { return solution_; }
  StopConditions::Reason stop_reason() const { return stop_reason_; }
  int last_iteration() const { return last_iteration_; }
  double last_mu() const { return last_mu_; }
  bool stalled() const { return stalled_; }
  bool stalled_in_restoration() const { return stalled_in_restoration_; }

 private:
  const Formulation& form_;
  const Phase phase_;
  const VectorXd start_;
  const StopConditions stop_;
  const int t_index_;  // the relaxation t (phase one only)
  const int num_vars_;
  std::vector<Entry> linear_;  // L, with the t column in phase one
  std::vector<Entry> hess_;    // structure of the Hessian
  std::vector<int> cone_hess_start_;    // 3x3 force block, per cone
  std::vector<int> cone_hess_s_start_;  // (s, f) row and (s, s), per cone
  const double stall_step_;  // primal steps below this count as stalled
  VectorXd solution_;
  StopConditions::Reason stop_reason_ = StopConditions::kNone;
  int last_iteration_ = 0;
  double last_mu_ = 0.0;
  int stall_count_ = 0;
  bool stalled_ = false;
  bool stalled_in_restoration_ = false;
};

// Sets every option explicitly; returns the names of rejected ones.
std::string ConfigureIpopt(Ipopt::IpoptApplication& app,
                           const PlanOptions& options, int max_iter,
                           bool has_cones, bool expect_infeasible) {
  Ipopt::OptionsList& o = *app.Options();
  std::string rejected;
  auto check = [&](bool ok, const char* name) {
    if (!ok) rejected += rejected.empty() ? name : std::string(", ") + name;
  };
  check(o.SetIntegerValue("print_level", 0), "print_level");
  check(o.SetStringValue("sb", "yes"), "sb");
  check(o.SetNumericValue("tol", options.ipopt_tolerance), "tol");
  check(o.SetIntegerValue("max_iter", max_iter), "max_iter");
  check(o.SetStringValue("mu_strategy", "monotone"), "mu_strategy");
  check(o.SetStringValue("linear_solver", "mumps"), "linear_solver");
  check(o.SetIntegerValue("mumps_pivot_order", 0), "mumps_pivot_order");
  // MUMPS workspace: 100% above its estimate instead of Ipopt's 1000%; the
  // allocation per factorisation dominated the run time of these tiny
  // systems (Ipopt doubles it and refactorises if MUMPS ever asks for more).
  check(o.SetIntegerValue("mumps_mem_percent", 100), "mumps_mem_percent");
  check(o.SetStringValue("jac_c_constant", "yes"), "jac_c_constant");
  if (!has_cones) {
    check(o.SetStringValue("jac_d_constant", "yes"), "jac_d_constant");
    check(o.SetStringValue("hessian_constant", "yes"), "hessian_constant");
  }
  // No relaxation of the bounds: the rows hold to Ipopt's tolerance (the
  // default 1e-8 relative relaxation let plans violate a 40 N bound by
  // 4e-7 N and differ from the geometric backend by up to 5e-6 N), and the
  // cone slacks s stay strictly positive (r divides by them).
  check(o.SetNumericValue("bound_relax_factor", 0.0), "bound_relax_factor");
  check(o.SetStringValue("expect_infeasible_problem",
                         expect_infeasible ? "yes" : "no"),
        "expect_infeasible_problem");
  return rejected;
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
           (status == Ipopt::Solve_Succeeded ||
            status == Ipopt::Solved_To_Acceptable_Level) &&
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
IpoptRun RunIpoptLocked(const Formulation& form, Phase phase, VectorXd start,
                        int max_iter, bool expect_infeasible,
                        const PlanOptions& options, const StopConditions& stop) {
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
    run.setup_error =
        std::string("Ipopt failed to initialise: ") + StatusName(run.status);
    return run;
  }
  run.status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));
  run.iterations = nlp->last_iteration();
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics();
      Ipopt::IsValid(stats)) {
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

IpoptRun RunIpopt(const Formulation& form, Phase phase, VectorXd start,
                  int max_iter, bool expect_infeasible,
                  const PlanOptions& options, const StopConditions& stop) {
  // Wait for the lock, still honouring an interrupt (the CPU budget does not
  // run down while blocked).
  std::unique_lock<std::timed_mutex> lock(MumpsMutex(), std::defer_lock);
  do {
    if (const StopConditions::Reason reason = stop.Check();
        reason != StopConditions::kNone) {
      IpoptRun run;
      run.stopped = reason;
      return run;
    }
  } while (!lock.try_lock_for(std::chrono::milliseconds(2)));
  return RunIpoptLocked(form, phase, std::move(start), max_iter,
                        expect_infeasible, options, stop);
}

class IpoptSolver final : public ForceSolver {
 public:
  IpoptSolver() : ForceSolver(SolverKind::kIpopt) {}

 protected:
  PlanResult DoSolve(const PreparedProblem& prepared,
                     const PlanOptions& options) const override {
    try {
      return SolveOrThrow(prepared, options);
    } catch (const Ipopt::IpoptException& e) {
      return Failure("Ipopt raised " + e.Message());
    } catch (const std::exception& e) {
      return Failure(std::string("Ipopt backend error: ") + e.what());
    } catch (...) {
      return Failure("Ipopt backend error: unknown exception");
    }
  }

 private:
  static PlanResult SolveOrThrow(const PreparedProblem& prepared,
                                 const PlanOptions& options) {
    const StopConditions stop{options.ipopt_max_cpu_seconds, ThreadCpuSeconds(),
                              &options.interrupt};
    const ForceEquilibrium& eq = prepared.equilibrium;
    if (!eq.consistent) {
      return Infeasible("the contacts cannot resist this wrench (rank " +
                        std::to_string(eq.rank) + " of G, residual " +
                        FormatNumber(eq.residual) + ")");
    }

    Formulation form;
    BuildOutcome built = BuildFormulation(prepared, options, &form);
    if (built.decided) return built.result;
    if (form.num_equilibrium >= form.num_forces) {
      return CheckUniqueEquilibrium(form, prepared);
    }

    int iterations = 0;
    auto finish = [&](PlanResult result) {
      result.iterations = iterations;
      return result;
    };
    auto stopped = [&](StopConditions::Reason reason) {
      const std::string after =
          " after " + std::to_string(iterations) + " Ipopt iterations";
      if (reason == StopConditions::kInterrupted) {
        return finish(Failure("interrupted" + after));
      }
      return finish(Failure("Ipopt stopped at the time limit (" +
                            FormatNumber(options.ipopt_max_cpu_seconds) +
                            " s CPU)" + after));
    };
    auto failed = [&](const IpoptRun& run) {
      if (!run.setup_error.empty()) return finish(Failure(run.setup_error));
      return finish(Failure(std::string("Ipopt failed: ") +
                            StatusName(run.status) + " after " +
                            std::to_string(iterations) + " iterations"));
    };
    // Solve_Succeeded / Solved_To_Acceptable_Level; or a run that stalled
    // (Search_Direction_Becomes_Too_Small, or our stall test) with the
    // barrier parameter at its final value and forces that meet every
    // constraint: a contact at a cone apex, where s >= 0 and r are both
    // active with parallel gradients and the dual infeasibility cannot reach
    // tol (see the file comment: feasible, optimality not certified).
    auto converged = [&](const IpoptRun& run, Phase phase) {
      if (run.succeeded()) return true;
      const bool stalled =
          run.status == Ipopt::Search_Direction_Becomes_Too_Small ||
          (run.status == Ipopt::User_Requested_Stop && run.stalled &&
           !run.stalled_in_restoration);
      if (!run.setup_error.empty() || run.stopped != StopConditions::kNone ||
          !stalled || run.solution.size() == 0 || !run.solution.allFinite()) {
        return false;
      }
      const double tol = kFeasibilityTolerance * form.scale;
      return run.last_mu <= 10.0 * options.ipopt_tolerance &&
             form.EquilibriumResidual(run.solution) <= tol &&
             (phase == Phase::kFeasibility ||
              form.MaxViolation(run.solution) <= tol);
    };
    auto optimal = [&](const IpoptRun& run) {
      PlanResult result;
      result.status = PlanStatus::kOptimal;
      if (run.status == Ipopt::Solved_To_Acceptable_Level) {
        result.message = "Ipopt: Solved_To_Acceptable_Level";
      } else if (run.status != Ipopt::Solve_Succeeded) {
        result.message =
            "Ipopt stalled at a cone apex (degenerate multipliers) with the "
            "barrier parameter at its final value; accepted: the forces meet "
            "every constraint, optimality not certified";
      }
      result.forces = form.Forces(run.solution.head(form.num_forces));
      return finish(result);
    };

    // 1. The minimum-norm problem, with Ipopt's quick infeasibility heuristic.
    const int max_iter = options.ipopt_max_iterations;
    const IpoptRun main =
        RunIpopt(form, Phase::kMinimumNorm, form.start,
                 std::min(max_iter, kFirstRunIterations), kExpectInfeasibleFirst,
                 options, stop);
    iterations += main.iterations;
    if (main.stopped != StopConditions::kNone) return stopped(main.stopped);
    if (converged(main, Phase::kMinimumNorm)) return optimal(main);
    if (!main.setup_error.empty()) return failed(main);
    if (main.status == Ipopt::Infeasible_Problem_Detected) {
      // Every constraint is convex (r = |P f|^2 / s - s is a perspective),
      // so the point of locally least violation Ipopt converged to is a
      // global one.
      std::string message = "Ipopt: Infeasible_Problem_Detected";
      if (main.solution.size() == form.num_vars()) {
        message += " (its point of least violation misses a constraint by " +
                   FormatNumber(form.MaxViolation(main.solution)) + " N)";
      }
      return finish(Infeasible(message));
    }

    // 2. Decide feasibility with the phase-one problem, started from the
    //    minimum-norm equilibrium with t above every violation.
    const int nv = form.num_vars();
    VectorXd start1(nv + 1);
    start1.head(nv) = form.start;
    const double t0 =
        std::max(0.0, form.MaxViolation(form.start)) + 1e-2 * form.scale;
    start1(nv) = t0;
    for (const ConeConstraint& cone : form.cones) {
      start1(cone.s_index) = cone.Radius(form.start.data()) + t0;
    }
    const IpoptRun phase1 = RunIpopt(form, Phase::kFeasibility, start1, max_iter,
                                     /*expect_infeasible=*/false, options, stop);
    iterations += phase1.iterations;
    if (phase1.stopped != StopConditions::kNone) return stopped(phase1.stopped);
    if (!converged(phase1, Phase::kFeasibility)) {
      return finish(Failure(
          std::string("Ipopt failed: ") + StatusName(main.status) +
          ", and the feasibility problem ended with " +
          StatusName(phase1.status) + " after " + std::to_string(iterations) +
          " iterations"));
    }
    VectorXd x1 = phase1.solution.head(nv);
    const double violation = form.MaxViolation(x1);
    if (violation > kInfeasibilityTolerance * form.scale) {
      return finish(Infeasible(
          std::string("Ipopt: ") + StatusName(main.status) +
          "; no equilibrium meets the tightened constraints (the least "
          "violation found is " + FormatNumber(violation) + " N)"));
    }

    // 3. Feasible after all: solve again, heuristic off, from the feasible
    //    point closest to the minimum-norm equilibrium on the segment between
    //    the two (phase one leaves internal forces arbitrarily large). Both
    //    ends satisfy the equilibrium; the constraints are convex, so the
    //    feasible part of the segment is an interval found by bisection.
    {
      const VectorXd direction = form.start - x1;
      double feasible = 0.0, infeasible = 1.0;
      const double tol = kFeasibilityTolerance * form.scale;
      if (form.MaxViolation(x1 + direction) <= tol) {
        feasible = 1.0;
      } else {
        for (int k = 0; k < 40; ++k) {
          const double mid = 0.5 * (feasible + infeasible);
          (form.MaxViolation(x1 + mid * direction) <= tol ? feasible : infeasible) = mid;
        }
      }
      x1 += 0.99 * feasible * direction;
    }
    for (const ConeConstraint& cone : form.cones) {
      x1(cone.s_index) = std::max({cone.Radius(x1.data()),
                                   cone.Tangential(x1.data()).norm(),
                                   1e-6 * form.scale});
    }
    const IpoptRun retry = RunIpopt(form, Phase::kMinimumNorm, x1, max_iter,
                                    /*expect_infeasible=*/false, options, stop);
    iterations += retry.iterations;
    if (retry.stopped != StopConditions::kNone) return stopped(retry.stopped);
    if (converged(retry, Phase::kMinimumNorm)) return optimal(retry);
    return failed(retry);
  }
};

}  // namespace

std::unique_ptr<ForceSolver> MakeIpoptSolver() {
  return std::make_unique<IpoptSolver>();
}

}  // namespace tactforce::planner::internal
