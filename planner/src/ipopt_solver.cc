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
#include <cmath>
#include <exception>
#include <limits>
#include <memory>
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
// Relative residual accepted for the re-reduced equilibrium rows.
constexpr double kEquilibriumTolerance = 1e-9;

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

// |P_t f|^2 - s^2 <= 0 for one contact with friction, s = mu n.f - shift.
struct ConeConstraint {
  int contact = 0;
  int offset = 0;  // first of the contact's three unknowns
  Vec3 normal = Vec3::UnitZ();
  double mu = 0.0;
  double shift = 0.0;  // kappa (mu rho_n + rho_t)

  double Slack(const Number* z) const {
    const Vec3 f(z[offset], z[offset + 1], z[offset + 2]);
    return mu * normal.dot(f) - shift;
  }
  double Value(const Number* z) const {
    const Vec3 f(z[offset], z[offset + 1], z[offset + 2]);
    const double fn = normal.dot(f);
    const double s = mu * fn - shift;
    return (f - fn * normal).squaredNorm() - s * s;
  }
  Vec3 Gradient(const Number* z) const {
    const Vec3 f(z[offset], z[offset + 1], z[offset + 2]);
    const double fn = normal.dot(f);
    const double s = mu * fn - shift;
    return 2.0 * (f - fn * normal) - 2.0 * s * mu * normal;
  }
  // 2 P_t - 2 mu^2 n n^T.
  Eigen::Matrix3d Hessian() const {
    return 2.0 * Eigen::Matrix3d::Identity() -
           2.0 * (1.0 + mu * mu) * normal * normal.transpose();
  }
};

// Where a linear row came from, for messages.
struct RowOrigin {
  enum Kind { kEquality, kPlanRow, kConeSlack } kind = kEquality;
  int index = 0;  // row of prepared.rows, or contact
};

// The NLP in the reduced unknowns z: f_i = z_i (3 unknowns) for contacts
// with friction, f_i = n_i z_i (1 unknown) for frictionless ones. The
// columns of this map are orthonormal, so |f|^2 = |z|^2.
struct Formulation {
  int num_vars = 0;
  std::vector<int> offset;          // per contact
  std::vector<bool> frictionless;   // per contact
  std::vector<Vec3> normal;         // per contact
  // Linear constraints lower <= L z <= upper; equalities come first.
  int num_equalities = 0;
  int num_linear = 0;
  std::vector<Entry> linear;  // L, sorted by row
  std::vector<double> lower;
  std::vector<double> upper;
  std::vector<RowOrigin> origin;
  std::vector<ConeConstraint> cones;
  VectorXd start;  // satisfies the equalities

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

  // Row values L z.
  VectorXd LinearValues(const Number* z) const {
    VectorXd values = VectorXd::Zero(num_linear);
    for (const Entry& e : linear) values(e.row) += e.value * z[e.col];
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

  // Unknowns.
  form->offset.resize(static_cast<size_t>(n));
  form->frictionless.resize(static_cast<size_t>(n));
  form->normal.resize(static_cast<size_t>(n));
  bool reduced = false;
  int num_vars = 0;
  for (int i = 0; i < n; ++i) {
    const Contact& c = problem.contacts[static_cast<size_t>(i)];
    form->offset[i] = num_vars;
    form->frictionless[i] = c.friction == 0.0;
    form->normal[i] = c.normal;
    num_vars += form->frictionless[i] ? 1 : 3;
    reduced = reduced || form->frictionless[i];
  }
  form->num_vars = num_vars;

  // T: f = T z (3n x num_vars), only needed when some contact is reduced.
  MatrixXd map;
  if (reduced) {
    map = MatrixXd::Zero(3 * n, num_vars);
    for (int i = 0; i < n; ++i) {
      if (form->frictionless[i]) {
        map.block<3, 1>(3 * i, form->offset[i]) = form->normal[i];
      } else {
        map.block<3, 3>(3 * i, form->offset[i]).setIdentity();
      }
    }
  }

  // Equalities.
  MatrixXd eq_rows;
  VectorXd eq_rhs;
  if (!reduced) {
    eq_rows = eq.independent_rows;
    eq_rhs = eq.independent_rhs;
    form->start = eq.particular;
  } else {
    const MatrixXd e = eq.independent_rows * map;
    const VectorXd& b = eq.independent_rhs;
    Eigen::JacobiSVD<MatrixXd> svd(e, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const VectorXd& sv = svd.singularValues();
    const double cutoff = sv.size() > 0 ? options.rank_tolerance * sv(0) : 0.0;
    int rank = 0;
    while (rank < sv.size() && sv(rank) > cutoff && sv(rank) > 0.0) ++rank;
    const MatrixXd u = svd.matrixU().leftCols(rank);
    eq_rhs = u.transpose() * b;
    eq_rows = u.transpose() * e;
    form->start = svd.matrixV().leftCols(rank) *
                  (eq_rhs.array() / sv.head(rank).array()).matrix();
    const double residual = (e * form->start - b).norm();
    if (!(residual <= kEquilibriumTolerance * std::max(1.0, b.norm()))) {
      return {true,
              Infeasible("the contacts cannot resist this wrench with the "
                         "frictionless contacts pushing only along their "
                         "normals (rank " + std::to_string(rank) +
                         " in the remaining unknowns, residual " +
                         FormatNumber(residual) + ")")};
    }
  }
  const int num_eq = static_cast<int>(eq_rows.rows());

  std::vector<Entry>& lin = form->linear;
  auto add_row = [&](const Eigen::Ref<const Eigen::RowVectorXd>& row,
                     double lo, double hi, RowOrigin origin) {
    const int r = static_cast<int>(form->lower.size());
    for (int j = 0; j < row.size(); ++j) {
      if (row(j) != 0.0) lin.push_back({r, j, row(j)});
    }
    form->lower.push_back(lo);
    form->upper.push_back(hi);
    form->origin.push_back(origin);
  };

  for (int k = 0; k < num_eq; ++k) {
    add_row(eq_rows.row(k), eq_rhs(k), eq_rhs(k), {RowOrigin::kEquality, k});
  }
  form->num_equalities = num_eq;

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
                                 FormatNumber(rows.rhs(k)) +
                                 " N below zero")};
      }
      continue;
    }
    add_row(a, -kInfinity, rows.rhs(k), {RowOrigin::kPlanRow, k});
  }

  // Exact friction cones.
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
      cone.normal = c.normal;
      cone.mu = c.friction;
      cone.shift = kappa * (c.friction * rho_n + rho_t);
      Eigen::RowVectorXd a = Eigen::RowVectorXd::Zero(num_vars);
      a.segment<3>(cone.offset) = cone.mu * c.normal.transpose();
      add_row(a, cone.shift, kInfinity, {RowOrigin::kConeSlack, i});
      form->cones.push_back(cone);
    }
  }
  form->num_linear = static_cast<int>(form->lower.size());
  return {};
}

// When the equalities determine z completely there is nothing to optimise:
// the unique equilibrium is the answer if it meets every constraint.
PlanResult CheckUniqueEquilibrium(const Formulation& form,
                                  const PreparedProblem& prepared) {
  const Number* z = form.start.data();
  const VectorXd values = form.LinearValues(z);
  for (int r = form.num_equalities; r < form.num_linear; ++r) {
    const double tol = kFeasibilityTolerance *
                       std::max({1.0, std::abs(form.lower[r]) < kInfinity
                                          ? std::abs(form.lower[r]) : 0.0,
                                 std::abs(form.upper[r]) < kInfinity
                                     ? std::abs(form.upper[r]) : 0.0});
    if (values(r) > form.upper[r] + tol || values(r) < form.lower[r] - tol) {
      const RowOrigin& o = form.origin[r];
      const std::string what =
          o.kind == RowOrigin::kPlanRow
              ? prepared.rows.Describe(o.index, prepared.problem)
              : ContactLabel(prepared.problem, o.index) + " friction cone";
      return Infeasible("the equilibrium forces are unique and violate " + what);
    }
  }
  for (const ConeConstraint& cone : form.cones) {
    const Vec3 f(z[cone.offset], z[cone.offset + 1], z[cone.offset + 2]);
    const double tangential = (f - cone.normal.dot(f) * cone.normal).norm();
    const double s = cone.Slack(z);
    if (tangential > s + kFeasibilityTolerance * std::max(1.0, f.norm())) {
      return Infeasible("the equilibrium forces are unique and violate " +
                        ContactLabel(prepared.problem, cone.contact) +
                        " friction cone");
    }
  }
  PlanResult result;
  result.status = PlanStatus::kOptimal;
  result.forces = form.Forces(form.start);
  result.iterations = 0;
  return result;
}

// The TNLP handed to Ipopt. Owned by one solve; not shared.
class ForceNlp final : public Ipopt::TNLP {
 public:
  ForceNlp(const Formulation& form, double cpu_limit_seconds)
      : form_(form),
        cpu_limit_seconds_(cpu_limit_seconds),
        cpu_start_seconds_(ThreadCpuSeconds()) {
    // Lower triangle of the Lagrangian Hessian: 2 I from the objective on
    // every unknown, plus the full 3x3 block of every cone.
    std::vector<bool> has_cone(form_.offset.size(), false);
    for (const ConeConstraint& c : form_.cones) {
      has_cone[static_cast<size_t>(c.contact)] = true;
    }
    for (size_t i = 0; i < form_.offset.size(); ++i) {
      const int o = form_.offset[i];
      if (form_.frictionless[i]) {
        hess_.push_back({o, o, 0.0});
      } else if (!has_cone[i]) {
        for (int a = 0; a < 3; ++a) hess_.push_back({o + a, o + a, 0.0});
      } else {
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b <= a; ++b) hess_.push_back({o + a, o + b, 0.0});
        }
      }
    }
    // Position of each cone's 3x3 block (6 entries, row-major lower) in hess_.
    cone_hess_start_.resize(form_.cones.size());
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      for (size_t e = 0; e < hess_.size(); ++e) {
        if (hess_[e].row == form_.cones[k].offset &&
            hess_[e].col == form_.cones[k].offset) {
          cone_hess_start_[k] = static_cast<int>(e);
          break;
        }
      }
    }
  }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override {
    n = form_.num_vars;
    m = form_.num_constraints();
    nnz_jac_g = static_cast<Index>(form_.linear.size() + 3 * form_.cones.size());
    nnz_h_lag = static_cast<Index>(hess_.size());
    index_style = C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                       Number* g_u) override {
    for (Index j = 0; j < n; ++j) {
      x_l[j] = -kInfinity;
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
      for (Index j = 0; j < n; ++j) x[j] = form_.start(j);
    }
    return true;
  }

  bool eval_f(Index n, const Number* x, bool new_x, Number& obj) override {
    obj = Eigen::Map<const VectorXd>(x, n).squaredNorm();
    return true;
  }

  bool eval_grad_f(Index n, const Number* x, bool new_x, Number* grad) override {
    for (Index j = 0; j < n; ++j) grad[j] = 2.0 * x[j];
    return true;
  }

  bool eval_g(Index n, const Number* x, bool new_x, Index m, Number* g) override {
    for (int r = 0; r < form_.num_linear; ++r) g[r] = 0.0;
    for (const Entry& e : form_.linear) g[e.row] += e.value * x[e.col];
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      g[form_.num_linear + k] = form_.cones[k].Value(x);
    }
    return true;
  }

  bool eval_jac_g(Index n, const Number* x, bool new_x, Index m, Index nele_jac,
                  Index* i_row, Index* j_col, Number* values) override {
    const size_t nl = form_.linear.size();
    if (values == nullptr) {
      for (size_t e = 0; e < nl; ++e) {
        i_row[e] = form_.linear[e].row;
        j_col[e] = form_.linear[e].col;
      }
      for (size_t k = 0; k < form_.cones.size(); ++k) {
        for (int a = 0; a < 3; ++a) {
          i_row[nl + 3 * k + a] = form_.num_linear + static_cast<Index>(k);
          j_col[nl + 3 * k + a] = form_.cones[k].offset + a;
        }
      }
      return true;
    }
    for (size_t e = 0; e < nl; ++e) values[e] = form_.linear[e].value;
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      const Vec3 grad = form_.cones[k].Gradient(x);
      for (int a = 0; a < 3; ++a) values[nl + 3 * k + a] = grad(a);
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
    for (size_t e = 0; e < hess_.size(); ++e) {
      values[e] = hess_[e].row == hess_[e].col ? 2.0 * obj_factor : 0.0;
    }
    for (size_t k = 0; k < form_.cones.size(); ++k) {
      const double weight = lambda[form_.num_linear + k];
      const Eigen::Matrix3d h = form_.cones[k].Hessian();
      int e = cone_hess_start_[k];
      for (int a = 0; a < 3; ++a) {
        for (int b = 0; b <= a; ++b) values[e++] += weight * h(a, b);
      }
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
    if (cpu_limit_seconds_ > 0.0 &&
        ThreadCpuSeconds() - cpu_start_seconds_ > cpu_limit_seconds_) {
      time_limit_reached_ = true;
      return false;
    }
    return true;
  }

  const VectorXd& solution() const { return solution_; }
  bool time_limit_reached() const { return time_limit_reached_; }
  int last_iteration() const { return last_iteration_; }

 private:
  const Formulation& form_;
  const double cpu_limit_seconds_;
  const double cpu_start_seconds_;
  std::vector<Entry> hess_;  // structure (values unused)
  std::vector<int> cone_hess_start_;
  VectorXd solution_;
  bool time_limit_reached_ = false;
  int last_iteration_ = 0;
};

// Sets every option explicitly; returns the names of rejected ones.
std::string ConfigureIpopt(Ipopt::IpoptApplication& app,
                           const PlanOptions& options, bool has_cones) {
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
  if (!has_cones) {
    check(o.SetStringValue("jac_d_constant", "yes"), "jac_d_constant");
    check(o.SetStringValue("hessian_constant", "yes"), "hessian_constant");
  }
  return rejected;
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
    const ForceEquilibrium& eq = prepared.equilibrium;
    if (!eq.consistent) {
      return Infeasible("the contacts cannot resist this wrench (rank " +
                        std::to_string(eq.rank) + " of G, residual " +
                        FormatNumber(eq.residual) + ")");
    }

    Formulation form;
    BuildOutcome built = BuildFormulation(prepared, options, &form);
    if (built.decided) return built.result;
    if (form.num_equalities >= form.num_vars) {
      return CheckUniqueEquilibrium(form, prepared);
    }

    Ipopt::SmartPtr<ForceNlp> nlp =
        new ForceNlp(form, options.ipopt_max_cpu_seconds);
    // No console journal: nothing is ever written to stdout.
    Ipopt::SmartPtr<Ipopt::IpoptApplication> app =
        new Ipopt::IpoptApplication(/*create_console_out=*/false);
    const std::string rejected =
        ConfigureIpopt(*app, options, !form.cones.empty());
    if (!rejected.empty()) {
      return Failure("Ipopt rejected the options: " + rejected);
    }
    // "" = do not read an ipopt.opt file from the working directory.
    Ipopt::ApplicationReturnStatus status = app->Initialize(std::string());
    if (status != Ipopt::Solve_Succeeded) {
      return Failure(std::string("Ipopt failed to initialise: ") +
                     StatusName(status));
    }
    status = app->OptimizeTNLP(Ipopt::GetRawPtr(nlp));

    PlanResult result;
    result.iterations = nlp->last_iteration();
    if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app->Statistics();
        Ipopt::IsValid(stats)) {
      result.iterations = stats->IterationCount();
    }
    const std::string after =
        " after " + std::to_string(result.iterations) + " iterations";

    switch (status) {
      case Ipopt::Solve_Succeeded:
      case Ipopt::Solved_To_Acceptable_Level:
        if (nlp->solution().size() != form.num_vars ||
            !nlp->solution().allFinite()) {
          return Failure(std::string("Ipopt reported ") + StatusName(status) +
                         " without a finite solution");
        }
        result.status = PlanStatus::kOptimal;
        if (status == Ipopt::Solved_To_Acceptable_Level) {
          result.message =
              "Ipopt: Solved_To_Acceptable_Level (accuracy below tol)";
        }
        result.forces = form.Forces(nlp->solution());
        return result;
      case Ipopt::Infeasible_Problem_Detected:
        result.status = PlanStatus::kInfeasible;
        result.message =
            "Ipopt: Infeasible_Problem_Detected (converged to a point of "
            "minimal constraint violation)" + after;
        return result;
      case Ipopt::Maximum_CpuTime_Exceeded:
        result.status = PlanStatus::kSolverFailure;
        result.message = "Ipopt stopped at the time limit (" +
                         FormatNumber(options.ipopt_max_cpu_seconds) +
                         " s CPU)" + after;
        return result;
      case Ipopt::User_Requested_Stop:
        if (nlp->time_limit_reached()) {
          result.status = PlanStatus::kSolverFailure;
          result.message = "Ipopt stopped at the time limit (" +
                           FormatNumber(options.ipopt_max_cpu_seconds) +
                           " s CPU)" + after;
          return result;
        }
        [[fallthrough]];
      default:
        result.status = PlanStatus::kSolverFailure;
        result.message = std::string("Ipopt failed: ") + StatusName(status) + after;
        return result;
    }
  }
};

}  // namespace

std::unique_ptr<ForceSolver> MakeIpoptSolver() {
  return std::make_unique<IpoptSolver>();
}

}  // namespace tactforce::planner::internal
