// Ipopt reference backend (SolverKind::kIpopt).
//
// Solves the force-planning problem directly with a general interior-point
// NLP solver, as an independent check of the geometric backend:
//
//   minimise   sum_i |f_i|^2                       (f in R^{3n})
//   subject to U_r^T G f = U_r^T b                  (independent equilibrium rows)
//              A f <= d                             (tightened linear rows)
//   EXACT cone, per contact i with mu_i > 0:
//              s_i(f) = mu_i (n_i . f_i - kappa rho_n,i) - kappa rho_t,i >= 0
//              |P_t f_i|^2 - s_i(f)^2 <= 0,      P_t = I - n_i n_i^T
//
// i.e. |P_t f_i| + kappa rho_t,i <= mu_i (n_i . f_i - kappa rho_n,i) in a
// smooth form, with exact first and second derivatives.
//
// Frictionless contacts (mu_i == 0) have a degenerate cone (a ray): their
// force is parametrised as f_i = n_i z_i with a single unknown z_i, for both
// cone models, instead of asking Ipopt to find the interior of a set that
// has none. The equilibrium rows are then re-reduced to full row rank in the
// reduced unknowns. When the equalities leave no freedom at all (e.g. a
// single contact) the unique equilibrium is checked directly.
//
// Ipopt settings (all set explicitly; no ipopt.opt file is read):
//   tol                 options.ipopt_tolerance (scaled overall NLP error)
//   max_iter            options.ipopt_max_iterations
//   print_level 0, sb yes, and no console journal: Ipopt never prints.
//   linear_solver       mumps (the only one in Debian's build)
//   mumps_pivot_order   0 (AMD): deterministic, and keeps SCOTCH/METIS
//                       orderings out of the multi-threaded server.
//   mu_strategy         monotone (Fiacco-McCormick). Compared with adaptive
//                       on the test grasps it needed a similar number of
//                       iterations and was the more reliable on degenerate
//                       and infeasible instances (see ipopt_solver_test).
//   hessian_constant, jac_d_constant  yes when there are no cone
//                       constraints (PYRAMID: a convex QP); jac_c_constant
//                       yes always (the equalities are always linear).
//   bound_relax_factor  left at Ipopt's 1e-8: rows may be violated by at
//                       most ~1e-8 max(1, |d|) N at the returned point.
// Time limit: options.ipopt_max_cpu_seconds > 0 is enforced on the CPU time
// of the calling thread (CLOCK_THREAD_CPUTIME_ID), checked by the
// intermediate callback after every iteration. Ipopt's own max_cpu_time is
// NOT used because Ipopt 3.11 measures it with getrusage(RUSAGE_SELF), the
// CPU time of the whole process: with several solves running concurrently
// in the server it would stop every solve far too early. (Ipopt, MUMPS-seq
// and the reference BLAS run single-threaded in the caller's thread, so the
// thread clock sees all of the work.)
//
// Thread safety: every call builds its own IpoptApplication, NLP and data;
// this file has no static mutable state. Ipopt 3.11.9 keeps its only global
// counter (TaggedObject) thread-local.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <functional>
#include <limits>
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
// Absolute feasibility slack (N) for the checks made without Ipopt (dropped
// rows of frictionless contacts, uniquely determined equilibria); the
// square roots inside rho_t and the row tightening make smaller round-off
// levels unreliable.
constexpr double kFeasibilityTolerance = 1e-8;
// Relative residual accepted for the re-reduced equilibrium rows (the same
// test ComputeForceEquilibrium applies to G f = b).
constexpr double kEquilibriumTolerance = 1e-8;
// The problem is declared infeasible when no point violates the tightened
// constraints by less than this times max(1, largest bound) (N).
constexpr double kInfeasibilityTolerance = 1e-7;

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

// One entry of a sparse matrix.
struct Entry {
  int row = 0;
  int col = 0;
  double value = 0.0;
};

// Exact friction cone of one contact with friction, in the unknowns
// (f_i, s_i): s_i is an extra unknown bounded below by zero and tied to the
// forces by the linear equality s_i - mu n.f_i = -shift. The cone itself is
//   r(f, s) = |P_t f|^2 / s - s <= 0   (s > 0),
// i.e. |P_t f| <= s. Unlike |P_t f|^2 - s^2 <= 0 its gradient never vanishes
// (dr/ds <= -1), so the constraint stays qualified at the apex f_i = 0 where
// unloaded contacts end up; and a violation of r by eps means |P_t f|
// exceeds s by about eps/2, not by sqrt(eps).
struct ConeConstraint {
  int contact = 0;
  int offset = 0;   // first of the contact's three force unknowns
  int s_index = 0;  // the slack unknown s
  Vec3 normal = Vec3::UnitZ();
  double mu = 0.0;
  double shift = 0.0;  // kappa (mu rho_n + rho_t): s = mu n.f - shift

  Vec3 Force(const Number* x) const {
    return Vec3(x[offset], x[offset + 1], x[offset + 2]);
  }
  Vec3 Tangential(const Number* x) const {
    const Vec3 f = Force(x);
    return f - normal.dot(f) * normal;
  }
  double Value(const Number* x) const {
    const double s = x[s_index];
    return Tangential(x).squaredNorm() / s - s;
  }
};

// Where a linear row came from, for messages.
struct RowOrigin {
  enum Kind { kEquality, kPlanRow, kConeSlack } kind = kEquality;
  int index = 0;  // row of prepared.rows, or contact
};

// The NLP. Unknowns x = (z, s): z are the reduced force unknowns
// (f_i = z_i, 3 unknowns, for contacts with friction; f_i = n_i z_i, one
// unknown, for frictionless ones; the map has orthonormal columns so
// |f|^2 = |z|^2), s the cone slacks (EXACT only).
struct Formulation {
  int num_forces = 0;               // unknowns in z
  std::vector<int> offset;          // per contact, into z
  std::vector<bool> frictionless;   // per contact
  std::vector<Vec3> normal;         // per contact
  int num_equilibrium = 0;          // equilibrium rows (the first rows)
  // Linear constraints lower <= L x <= upper.
  int num_linear = 0;
  std::vector<Entry> linear;
  std::vector<double> lower;
  std::vector<double> upper;
  std::vector<RowOrigin> origin;
  std::vector<ConeConstraint> cones;
  VectorXd start;  // (z0, s0); z0 satisfies the equilibrium rows

  int num_vars() const { return num_forces + static_cast<int>(cones.size()); }
  int num_constraints() const {
    return num_linear + static_cast<int>(cones.size());
  }

  std::vector<Vec3> Forces(const VectorXd& x) const {
    std::vector<Vec3> forces(offset.size());
    for (size_t i = 0; i < offset.size(); ++i) {
      forces[i] = frictionless[i] ? Vec3(normal[i] * x(offset[i]))
                                  : Vec3(x.segment<3>(offset[i]));
    }
    return forces;
  }

  // Row values L x.
  VectorXd LinearValues(const Number* x) const {
    VectorXd values = VectorXd::Zero(num_linear);
    for (const Entry& e : linear) values(e.row) += e.value * x[e.col];
    return values;
  }
};

// Outcome of building the formulation: either a formulation to solve or a
// final answer found on the way.
struct BuildOutcome {
  bool decided = false;
  PlanResult result;
};

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

BuildOutcome BuildFormulation(const PreparedProblem& prepared,
                              const PlanOptions& options, Formulation* form) {
  const PlanProblem& problem = prepared.problem;
  const ForceEquilibrium& eq = prepared.equilibrium;
  const int n = prepared.num_contacts();
  const bool exact = options.cone == ConeModel::kExact;
  const double kappa = options.confidence;

  // Force unknowns.
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

  // Equilibrium rows, full row rank in z.
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
    while (rank < sv.size() && sv(rank) > cutoff && sv(rank) > 0.0) ++rank;
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

  std::vector<Entry>& lin = form->linear;
  auto add_row = [&](const std::vector<std::pair<int, double>>& terms,
                     double lo, double hi, RowOrigin origin) {
    const int r = static_cast<int>(form->lower.size());
    for (const auto& [col, value] : terms) {
      if (value != 0.0) lin.push_back({r, col, value});
    }
    form->lower.push_back(lo);
    form->upper.push_back(hi);
    form->origin.push_back(origin);
  };
  auto dense_terms = [](const Eigen::RowVectorXd& row) {
    std::vector<std::pair<int, double>> terms;
    for (int j = 0; j < row.size(); ++j) terms.emplace_back(j, row(j));
    return terms;
  };

  for (int k = 0; k < eq_rows.rows(); ++k) {
    add_row(dense_terms(eq_rows.row(k)), eq_rhs(k), eq_rhs(k),
            {RowOrigin::kEquality, k});
  }
  form->num_equilibrium = static_cast<int>(eq_rows.rows());

  // Tightened linear rows A f <= d.
  const ConstraintRows& rows = prepared.rows;
  for (int k = 0; k < rows.matrix.rows(); ++k) {
    Eigen::RowVectorXd a = rows.matrix.row(k);
    if (reduced) a = a * map;
    const double scale = rows.matrix.row(k).cwiseAbs().maxCoeff();
    if (a.cwiseAbs().maxCoeff() <= 1e-12 * scale) {
      // The row does not depend on the unknowns left (a friction facet of a
      // frictionless contact): 0 <= d must hold by itself.
      const double slack_tol =
          kFeasibilityTolerance * std::max(1.0, std::abs(rows.nominal_rhs(k)));
      if (rows.rhs(k) < -slack_tol) {
        return {true, Infeasible(rows.Describe(k, problem) +
                                 " cannot be met: its robust bound is " +
                                 FormatNumber(rows.rhs(k)) + " N below zero")};
      }
      continue;
    }
    add_row(dense_terms(a), -kInfinity, rows.rhs(k), {RowOrigin::kPlanRow, k});
  }

  // Exact friction cones: s_i - mu n.f_i = -shift, s_i >= 0, r_i <= 0.
  if (exact) {
    for (int i = 0; i < n; ++i) {
      const Contact& c = problem.contacts[static_cast<size_t>(i)];
      const double rho_n = prepared.normal_sigma[static_cast<size_t>(i)];
      const double rho_t = prepared.tangential_sigma[static_cast<size_t>(i)];
      if (form->frictionless[i]) {
        // |P_t f| + kappa rho_t <= 0: only the tangential uncertainty matters.
        if (kappa * rho_t > kFeasibilityTolerance) {
          return {true,
                  Infeasible(ContactLabel(problem, i) +
                             " is frictionless but its tangential force "
                             "uncertainty kappa*rho_t = " +
                             FormatNumber(kappa * rho_t) +
                             " N cannot be resisted")};
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

  // Start: the minimum-norm equilibrium and its cone slacks (clipped at the
  // bound; Ipopt pushes them inside).
  form->start = VectorXd::Zero(form->num_vars());
  form->start.head(num_forces) = z0;
  for (const ConeConstraint& cone : form->cones) {
    const double s = cone.mu * cone.normal.dot(cone.Force(form->start.data())) -
                     cone.shift;
    form->start(cone.s_index) = std::max(s, 0.0);
  }
  return {};
}

// When the equilibrium rows determine the forces completely there is nothing
// to optimise: the unique equilibrium is the answer if it meets every
// constraint.
PlanResult CheckUniqueEquilibrium(const Formulation& form,
                                  const PreparedProblem& prepared) {
  const Number* x = form.start.data();
  const VectorXd values = form.LinearValues(x);
  for (int r = form.num_equilibrium; r < form.num_linear; ++r) {
    const RowOrigin& o = form.origin[r];
    if (o.kind != RowOrigin::kPlanRow) continue;  // cone slacks: below
    const double tol =
        kFeasibilityTolerance * std::max(1.0, std::abs(form.upper[r]));
    if (values(r) > form.upper[r] + tol) {
      return Infeasible("the equilibrium forces are unique and violate " +
                        prepared.rows.Describe(o.index, prepared.problem));
    }
  }
  for (const ConeConstraint& cone : form.cones) {
    const Vec3 f = cone.Force(x);
    const double s = cone.mu * cone.normal.dot(f) - cone.shift;
    if (cone.Tangential(x).norm() >
        s + kFeasibilityTolerance * std::max(1.0, f.norm())) {
      return Infeasible("the equilibrium forces are unique and violate the "
                        "friction cone of " +
                        ContactLabel(prepared.problem, cone.contact));
    }
  }
  PlanResult result;
  result.status = PlanStatus::kOptimal;
  result.forces = form.Forces(form.start);
  result.iterations = 0;
  return result;
}

// Which problem the TNLP poses.
enum class Phase {
  // min |f|^2 over the constraints (the answer).
  kMinimumNorm,
  // Feasibility: min t >= 0 with every inequality relaxed by t (plan rows
  // a.f <= d + t, cone slacks s = s(f) + t); the equilibrium stays exact.
  // Always feasible; optimal t > 0 proves the problem infeasible.
  kFeasibility,
};

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

// The TNLP handed to Ipopt. Owned by one run; not shared.
class ForceNlp final : public Ipopt::TNLP {
 public:
  ForceNlp(const Formulation& form, Phase phase, VectorXd start,
           const StopConditions& stop)
      : form_(form),
        phase_(phase),
        start_(std::move(start)),
        stop_(stop),
        num_vars_(form.num_vars() + (phase == Phase::kFeasibility ? 1 : 0)),
        t_index_(form.num_vars()),
        linear_(form.linear) {
    if (phase_ == Phase::kFeasibility) {
      for (int r = 0; r < form_.num_linear; ++r) {
        if (form_.origin[r].kind != RowOrigin::kEquality) {
          linear_.push_back({r, t_index_, -1.0});
        }
      }
    }
    // Lower triangle of the Lagrangian Hessian: the diagonal of every force
    // unknown (2 I from the objective); for a cone the 3x3 force block, the
    // (s, f) row and (s, s).
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
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      const ConeConstraint& c = form_.cones[k];
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
    for (int r = 0; r < form_.num_linear; ++r) g[r] = 0.0;
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
      // dr/df = 2 P_t f / s, dr/ds = -|P_t f|^2 / s^2 - 1.
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
      // d2r/df2 = 2 P_t / s, d2r/dsdf = -2 P_t f / s^2,
      // d2r/ds2 = 2 |P_t f|^2 / s^3.
      const Eigen::Matrix3d p =
          Eigen::Matrix3d::Identity() - c.normal * c.normal.transpose();
      int e = cone_hess_start_[k];
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b <= a; ++b) values[e++] += weight * 2.0 * p(a, b) / s;
      }
      e = cone_hess_s_start_[k];
      for (int a = 0; a < 3; ++a) values[e++] += weight * -2.0 * w(a) / (s * s);
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
    stop_reason_ = stop_.Check();
    return stop_reason_ == StopConditions::kNone;
  }

  const VectorXd& solution() const { return solution_; }
  StopConditions::Reason stop_reason() const { return stop_reason_; }
  int last_iteration() const { return last_iteration_; }

 private:
  const Formulation& form_;
  const Phase phase_;
  const VectorXd start_;
  const StopConditions stop_;
  const int num_vars_;
  const int t_index_;           // feasibility phase only
  std::vector<Entry> linear_;   // L, plus the t column in the feasibility phase
  std::vector<Entry> hess_;     // structure (values unused)
  std::vector<int> cone_hess_start_;    // 3x3 force block, per cone
  std::vector<int> cone_hess_s_start_;  // (s, f) row and (s, s), per cone
  VectorXd solution_;
  StopConditions::Reason stop_reason_ = StopConditions::kNone;
  int last_iteration_ = 0;
};

// Sets every option explicitly; returns the names of rejected ones.
std::string ConfigureIpopt(Ipopt::IpoptApplication& app,
                           const PlanOptions& options, bool has_cones,
                           bool expect_infeasible) {
  Ipopt::OptionsList& o = *app.Options();
  std::string rejected;
  auto check = [&](bool ok, const char* name) {
    if (!ok) rejected += rejected.empty() ? name : std::string(", ") + name;
  };
  check(o.SetIntegerValue("print_level", 0), "print_level");
  check(o.SetStringValue("sb", "yes"), "sb");
  check(o.SetNumericValue("tol", options.ipopt_tolerance), "tol");
  check(o.SetIntegerValue("max_iter", options.ipopt_max_iterations), "max_iter");
  check(o.SetStringValue("mu_strategy", "monotone"), "mu_strategy");
  check(o.SetStringValue("linear_solver", "mumps"), "linear_solver");
  check(o.SetIntegerValue("mumps_pivot_order", 0), "mumps_pivot_order");
  check(o.SetStringValue("jac_c_constant", "yes"), "jac_c_constant");
  check(o.SetStringValue("expect_infeasible_problem",
                         expect_infeasible ? "yes" : "no"),
        "expect_infeasible_problem");
  if (!has_cones) {
    check(o.SetStringValue("jac_d_constant", "yes"), "jac_d_constant");
    check(o.SetStringValue("hessian_constant", "yes"), "hessian_constant");
  } else {
    // The cone slacks s must stay strictly positive (r divides by s).
    check(o.SetNumericValue("bound_relax_factor", 0.0), "bound_relax_factor");
  }
  return rejected;
}

// One Ipopt run.
struct IpoptRun {
  Ipopt::ApplicationReturnStatus status = Ipopt::Internal_Error;
  std::string setup_error;  // non-empty: Ipopt did not run
  int iterations = 0;
  StopConditions::Reason stopped = StopConditions::kNone;
  VectorXd solution;  // valid when status is a success

  bool succeeded() const {
    return setup_error.empty() &&
           (status == Ipopt::Solve_Succeeded ||
            status == Ipopt::Solved_To_Acceptable_Level) &&
           solution.allFinite();
  }
};

// Debian's sequential MUMPS (libdmumps_seq 5.5) keeps Fortran module state
// and is not thread-safe: two Ipopt solves at once abort the process
// ("PB allocation in DMUMPS_LOAD_INIT ... MPI_ABORT"). Each IpoptApplication
// therefore lives, from construction to destruction (MUMPS is initialised
// and terminated with it), under this process-wide lock. Only the Ipopt run
// itself is serialised; building the formulation is not.
std::timed_mutex& MumpsMutex() {
  static std::timed_mutex mutex;
  return mutex;
}

// One Ipopt run; the caller holds MumpsMutex(). Everything Ipopt allocates
// is released before this returns.
IpoptRun RunIpoptLocked(const Formulation& form, Phase phase, VectorXd start,
                        bool expect_infeasible, const PlanOptions& options,
                        const StopConditions& stop) {
  IpoptRun run;
  const int num_vars =
      form.num_vars() + (phase == Phase::kFeasibility ? 1 : 0);
  Ipopt::SmartPtr<ForceNlp> nlp =
      new ForceNlp(form, phase, std::move(start), stop);
  // No console journal: nothing is ever written to stdout.
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app =
      new Ipopt::IpoptApplication(/*create_console_out=*/false);
  const std::string rejected =
      ConfigureIpopt(*app, options, !form.cones.empty(), expect_infeasible);
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
  if (run.status == Ipopt::Maximum_CpuTime_Exceeded) {
    run.stopped = StopConditions::kTimeLimit;  // not set by us; kept for safety
  }
  if (nlp->solution().size() == num_vars) run.solution = nlp->solution();
  return run;
}

IpoptRun RunIpopt(const Formulation& form, Phase phase, VectorXd start,
                  bool expect_infeasible, const PlanOptions& options,
                  const StopConditions& stop) {
  // Wait for the lock, still honouring an interrupt (the CPU-time budget
  // does not run down while blocked).
  std::unique_lock<std::timed_mutex> lock(MumpsMutex(), std::defer_lock);
  do {
    if (StopConditions::Reason reason = stop.Check();
        reason != StopConditions::kNone) {
      IpoptRun run;
      run.stopped = reason;
      return run;
    }
  } while (!lock.try_lock_for(std::chrono::milliseconds(2)));
  return RunIpoptLocked(form, phase, std::move(start), expect_infeasible,
                        options, stop);
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
        return Failure("interrupted" + after);
      }
      return Failure("Ipopt stopped at the time limit (" +
                     FormatNumber(options.ipopt_max_cpu_seconds) +
                     " s CPU)" + after);
    };
    auto optimal = [&](const IpoptRun& run) {
      PlanResult result;
      result.status = PlanStatus::kOptimal;
      if (run.status == Ipopt::Solved_To_Acceptable_Level) {
        result.message = "Ipopt: Solved_To_Acceptable_Level";
      }
      result.forces = form.Forces(run.solution);
      return result;
    };

    // 1. The minimum-norm problem, with Ipopt's heuristic for infeasible
    //    problems on (without it Ipopt can spend thousands of iterations
    //    before giving up on an infeasible EXACT problem).
    IpoptRun main = RunIpopt(form, Phase::kMinimumNorm, form.start,
                             /*expect_infeasible=*/true, options, stop);
    iterations += main.iterations;
    if (!main.setup_error.empty()) return finish(Failure(main.setup_error));
    if (main.succeeded()) return finish(optimal(main));
    if (main.stopped != StopConditions::kNone) return finish(stopped(main.stopped));

    // 2. No optimum: decide feasibility with the always-feasible phase-one
    //    problem, started from the minimum-norm equilibrium with t large
    //    enough for every relaxed constraint to hold.
    VectorXd start1 = VectorXd::Zero(form.num_vars() + 1);
    start1.head(form.num_vars()) = form.start;
    const VectorXd row_values = form.LinearValues(form.start.data());
    double t0 = 0.0;
    for (int r = 0; r < form.num_linear; ++r) {
      if (form.origin[r].kind == RowOrigin::kPlanRow) {
        t0 = std::max(t0, row_values(r) - form.upper[r]);
      }
    }
    for (const ConeConstraint& cone : form.cones) {
      const Vec3 f = cone.Force(form.start.data());
      const double s = cone.mu * cone.normal.dot(f) - cone.shift;
      t0 = std::max(t0, cone.Tangential(form.start.data()).norm() - s);
    }
    double scale = 1.0;
    for (int r = 0; r < form.num_linear; ++r) {
      if (std::abs(form.upper[r]) < kInfinity) {
        scale = std::max(scale, std::abs(form.upper[r]));
      }
      if (std::abs(form.lower[r]) < kInfinity) {
        scale = std::max(scale, std::abs(form.lower[r]));
      }
    }
    t0 += 1e-2 * scale;
    start1(form.num_vars()) = t0;
    for (const ConeConstraint& cone : form.cones) {
      const Vec3 f = cone.Force(form.start.data());
      start1(cone.s_index) = cone.mu * cone.normal.dot(f) - cone.shift + t0;
    }
    IpoptRun phase1 = RunIpopt(form, Phase::kFeasibility, start1,
                               /*expect_infeasible=*/false, options, stop);
    iterations += phase1.iterations;
    if (phase1.stopped != StopConditions::kNone) {
      return finish(stopped(phase1.stopped));
    }
    if (!phase1.succeeded()) {
      // Fall back on the verdict of the main run.
      if (main.status == Ipopt::Infeasible_Problem_Detected) {
        return finish(Infeasible(
            "Ipopt: Infeasible_Problem_Detected (not confirmed: the "
            "feasibility problem ended with " +
            std::string(StatusName(phase1.status)) + ")"));
      }
      return finish(Failure(std::string("Ipopt failed: ") +
                            StatusName(main.status) + " after " +
                            std::to_string(iterations) + " iterations"));
    }
    const double violation = phase1.solution(form.num_vars());
    if (violation > kInfeasibilityTolerance * scale) {
      return finish(Infeasible(
          std::string("Ipopt: ") + StatusName(main.status) +
          "; the feasibility problem shows the tightened constraints are "
          "violated by at least " + FormatNumber(violation) + " N"));
    }

    // 3. Feasible after all: solve again from the feasible point, without the
    //    infeasibility heuristic.
    IpoptRun retry = RunIpopt(form, Phase::kMinimumNorm,
                              phase1.solution.head(form.num_vars()),
                              /*expect_infeasible=*/false, options, stop);
    iterations += retry.iterations;
    if (!retry.setup_error.empty()) return finish(Failure(retry.setup_error));
    if (retry.succeeded()) return finish(optimal(retry));
    if (retry.stopped != StopConditions::kNone) {
      return finish(stopped(retry.stopped));
    }
    return finish(Failure(std::string("Ipopt failed: ") +
                          StatusName(retry.status) + " after " +
                          std::to_string(iterations) + " iterations"));
  }
};

}  // namespace

std::unique_ptr<ForceSolver> MakeIpoptSolver() {
  return std::make_unique<IpoptSolver>();
}

}  // namespace tactforce::planner::internal
