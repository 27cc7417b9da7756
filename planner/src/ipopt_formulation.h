// Internal to the Ipopt backend: the NLP data built from a PreparedProblem
// (unknowns, sparse linear rows, exact cones, start point), independent of
// Ipopt itself. ipopt_nlp.h poses it to Ipopt; ipopt_solver.cc drives it.
//
//   minimise   sum_i |f_i|^2                              (f in R^{3n}, N)
//   subject to U_r^T G f = U_r^T b         (independent equilibrium rows)
//              A f <= d                    (robustly tightened linear rows)
//   EXACT, per contact i with mu_i > 0 (P = I - n_i n_i^T):
//              |P f_i| <= mu_i n_i . f_i - shift_i   (PreparedProblem::cone_shift)
//
// Each exact cone gets a slack unknown s_i = mu_i n_i . f_i - shift_i (a
// linear row), bounded by s_i >= 0, and the convex constraint
// r_i(f, s) = |P f_i|^2 / s_i - s_i <= 0 (see ipopt_nlp.h for why this form).
//
// Frictionless contacts (mu_i == 0) have a cone with no interior (a ray):
// their force is parametrised as f_i = n_i z_i, for both cone models. The
// equilibrium rows are then re-reduced to full row rank in the reduced
// unknowns, and friction facets of such a contact become bound checks made
// while building.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "tactforce/planner/force_model.h"
#include "tactforce/planner/types.h"

namespace tactforce::planner::internal {

// Any bound beyond Ipopt's nlp_{lower,upper}_bound_inf (1e19) is infinite.
inline constexpr double kInfinity = 1e20;
// Absolute slack (N) for the checks made without Ipopt (facets of
// frictionless contacts, uniquely determined equilibria, stalled runs): rho_t
// and the row tightening take square roots, so round-off can reach ~1e-9 N.
inline constexpr double kFeasibilityTolerance = 1e-8;

// `value` with 4 significant digits, for messages.
std::string FormatNumber(double value);

// One entry of a sparse matrix.
struct Entry {
  int row = 0;
  int col = 0;
  double value = 0.0;
};

// The exact cone of one contact with friction: |P f| <= s with the slack
// unknown s = mu n.f - shift >= 0, posed as r(f, s) = |P f|^2 / s - s <= 0.
// x points at the NLP unknowns (at least up to s_index).
struct ConeConstraint {
  int contact = 0;
  int offset = 0;               // first of the contact's three force unknowns
  int s_index = 0;              // the slack unknown s
  Vec3 normal = Vec3::UnitZ();  // unit, into the object
  double mu = 0.0;
  double shift = 0.0;  // PreparedProblem::cone_shift of the contact (N)

  Vec3 Force(const double* x) const { return Vec3(x[offset], x[offset + 1], x[offset + 2]); }
  Vec3 Tangential(const double* x) const {
    const Vec3 f = Force(x);
    return f - normal.dot(f) * normal;
  }
  // s(f): the cone radius available at the forces in x (N).
  double Radius(const double* x) const { return mu * normal.dot(Force(x)) - shift; }
  // |P f| - s(f): > 0 outside the cone (N).
  double Violation(const double* x) const { return -ExactConeSlack(normal, mu, shift, Force(x)); }
  // r(f, s) with the slack s = x[s_index] > 0.
  double Value(const double* x) const {
    const double s = x[s_index];
    return Tangential(x).squaredNorm() / s - s;
  }
};

// Where a linear row came from.
struct RowOrigin {
  enum Kind { kEquilibrium, kPlanRow, kConeSlack } kind = kEquilibrium;
  int index = 0;  // row of PreparedProblem::rows (kPlanRow), or contact
};

// The NLP. Unknowns x = (z, s): z are the reduced forces, f_i = z_i (3
// unknowns) for contacts with friction and f_i = n_i z_i (1 unknown) for
// frictionless ones (orthonormal map, so |f|^2 = |z|^2); s are the cone
// slacks (EXACT only). Constraints: the linear rows, then one r_i per cone.
struct Formulation {
  int num_forces = 0;              // unknowns in z
  std::vector<int> offset;         // per contact: its first unknown in z
  std::vector<bool> frictionless;  // per contact
  std::vector<Vec3> normal;        // per contact, unit
  // Linear constraints lower <= L x <= upper: the equilibrium rows first
  // (lower == upper), then plan rows (lower = -kInfinity), then cone-slack
  // rows s_i - mu_i n_i . f_i = -shift_i.
  int num_equilibrium = 0;
  int num_linear = 0;
  std::vector<Entry> linear;  // L, entries in row order
  std::vector<double> lower;
  std::vector<double> upper;
  std::vector<RowOrigin> origin;
  std::vector<ConeConstraint> cones;  // constraints num_linear, ...
  Eigen::VectorXd start;              // (z0, s0): the minimum-norm equilibrium, r <= 0
  double scale = 1.0;                 // max(1, largest finite row bound), N

  int num_vars() const { return num_forces + static_cast<int>(cones.size()); }
  int num_constraints() const { return num_linear + static_cast<int>(cones.size()); }

  // Per-contact forces (object frame, N) of the reduced forces z.
  std::vector<Vec3> Forces(const Eigen::VectorXd& z) const;
  // L x for x = (z, s, ...).
  Eigen::VectorXd LinearValues(const double* x) const;
  // Largest violation (N) of the plan rows and exact cones at the forces in
  // x (the slacks in x are ignored); 0 when all hold.
  double MaxViolation(const Eigen::VectorXd& x) const;
  // Largest |residual| of the equilibrium rows at x.
  double EquilibriumResidual(const Eigen::VectorXd& x) const;
};

// Either the formulation to solve, or why building it already proved the
// problem infeasible (then `form` is incomplete).
struct FormulationOutcome {
  Formulation form;
  std::string infeasible;  // non-empty: the INFEASIBLE message
};

// Requires prepared.equilibrium.consistent. Uses options.cone and
// options.rank_tolerance; the tightening comes from `prepared`.
FormulationOutcome BuildFormulation(const PreparedProblem& prepared, const PlanOptions& options);

}  // namespace tactforce::planner::internal
