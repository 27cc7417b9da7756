// Builds the Ipopt backend's NLP data (ipopt_formulation.h) from a
// PreparedProblem, in named steps: unknowns, equilibrium rows, plan rows,
// exact cones, start point.
#include "planner/src/ipopt_formulation.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include <Eigen/SVD>

namespace tactforce::planner::internal {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

// Relative residual accepted for the re-reduced equilibrium rows (the same
// test ComputeForceEquilibrium applies to G f = b).
constexpr double kEquilibriumTolerance = 1e-8;

using Terms = std::vector<std::pair<int, double>>;  // (column, value)

// Offsets, normals and frictionless flags of every contact, and num_forces.
// Returns whether any contact is reduced to its normal (frictionless).
bool AssignUnknowns(const PlanProblem& problem, Formulation* form) {
  const size_t n = problem.contacts.size();
  form->offset.resize(n);
  form->frictionless.resize(n);
  form->normal.resize(n);
  bool reduced = false;
  int num_forces = 0;
  for (size_t i = 0; i < n; ++i) {
    const Contact& c = problem.contacts[i];
    form->offset[i] = num_forces;
    form->frictionless[i] = c.friction == 0.0;
    form->normal[i] = c.normal;
    num_forces += form->frictionless[i] ? 1 : 3;
    reduced = reduced || form->frictionless[i];
  }
  form->num_forces = num_forces;
  return reduced;
}

// T with f = T z (3n x num_forces).
MatrixXd ForceMap(const Formulation& form) {
  const int n = static_cast<int>(form.offset.size());
  MatrixXd map = MatrixXd::Zero(3 * n, form.num_forces);
  for (int i = 0; i < n; ++i) {
    if (form.frictionless[i]) {
      map.block<3, 1>(3 * i, form.offset[i]) = form.normal[i];
    } else {
      map.block<3, 3>(3 * i, form.offset[i]).setIdentity();
    }
  }
  return map;
}

// Equilibrium rows of full row rank in z, and their minimum-norm solution.
struct EquilibriumInUnknowns {
  MatrixXd rows;
  VectorXd rhs;
  VectorXd start;
  std::string infeasible;  // non-empty: no z meets the rows
};

// `map` == nullptr: z = f, the rows of `eq` as they are.
EquilibriumInUnknowns ReduceEquilibrium(const ForceEquilibrium& eq, const MatrixXd* map,
                                        double rank_tolerance) {
  EquilibriumInUnknowns out;
  if (map == nullptr) {
    out.rows = eq.independent_rows;
    out.rhs = eq.independent_rhs;
    out.start = eq.particular;
    return out;
  }
  const MatrixXd e = eq.independent_rows * *map;
  const VectorXd& b = eq.independent_rhs;
  Eigen::JacobiSVD<MatrixXd> svd(e, Eigen::ComputeThinU | Eigen::ComputeThinV);
  const VectorXd& sv = svd.singularValues();
  const double cutoff = sv.size() > 0 ? rank_tolerance * std::max(1.0, sv(0)) : 0.0;
  int rank = 0;
  while (rank < sv.size() && sv(rank) > cutoff) ++rank;
  const MatrixXd u = svd.matrixU().leftCols(rank);
  out.rhs = u.transpose() * b;
  out.rows = u.transpose() * e;
  out.start = svd.matrixV().leftCols(rank) * (out.rhs.array() / sv.head(rank).array()).matrix();
  const double residual = (e * out.start - b).norm();
  if (!(residual <= kEquilibriumTolerance * std::max(1.0, b.norm()))) {
    out.infeasible =
        "the contacts cannot resist this wrench with the frictionless contacts pushing only "
        "along their normals (rank " +
        std::to_string(rank) + " in the remaining unknowns, residual " + FormatNumber(residual) +
        ")";
  }
  return out;
}

// Appends lower <= terms . x <= upper (zero terms dropped) and widens scale.
void AddRow(const Terms& terms, double lower, double upper, RowOrigin origin, Formulation* form) {
  const int r = static_cast<int>(form->lower.size());
  for (const auto& [col, value] : terms) {
    if (value != 0.0) form->linear.push_back({r, col, value});
  }
  form->lower.push_back(lower);
  form->upper.push_back(upper);
  form->origin.push_back(origin);
  if (std::abs(lower) < kInfinity) form->scale = std::max(form->scale, std::abs(lower));
  if (std::abs(upper) < kInfinity) form->scale = std::max(form->scale, std::abs(upper));
}

Terms DenseTerms(const Eigen::RowVectorXd& row) {
  Terms terms;
  for (int j = 0; j < row.size(); ++j) terms.emplace_back(j, row(j));
  return terms;
}

void AddEquilibriumRows(const EquilibriumInUnknowns& eq, Formulation* form) {
  for (int k = 0; k < eq.rows.rows(); ++k) {
    AddRow(DenseTerms(eq.rows.row(k)), eq.rhs(k), eq.rhs(k), {RowOrigin::kEquilibrium, k}, form);
  }
  form->num_equilibrium = static_cast<int>(eq.rows.rows());
}

// The tightened rows A f <= d in z (`map` as for ReduceEquilibrium). A row
// left without unknowns (a friction facet of a frictionless contact) must
// hold by itself, 0 <= d; returns the INFEASIBLE message when one does not.
std::string AddPlanRows(const PreparedProblem& prepared, const MatrixXd* map, Formulation* form) {
  const ConstraintRows& rows = prepared.rows;
  const MatrixXd dense = rows.Dense(prepared.num_contacts());
  for (int k = 0; k < dense.rows(); ++k) {
    Eigen::RowVectorXd a = dense.row(k);
    if (map != nullptr) a = a * *map;
    const double size = dense.row(k).cwiseAbs().maxCoeff();
    if (a.cwiseAbs().maxCoeff() <= 1e-12 * size) {
      if (rows.rhs(k) < -kFeasibilityTolerance * std::max(1.0, std::abs(rows.nominal_rhs(k)))) {
        return rows.Describe(k, prepared.problem) + " cannot be met: its robust bound is " +
               FormatNumber(rows.rhs(k)) + " N";
      }
      continue;
    }
    AddRow(DenseTerms(a), -kInfinity, rows.rhs(k), {RowOrigin::kPlanRow, k}, form);
  }
  return {};
}

// Exact friction cones: the row s_i - mu n.f_i = -shift_i per contact with
// friction (r_i itself is posed by the NLP). A frictionless contact's cone
// is |P f| + shift <= 0 with P f = 0: only the uncertainty is left, so it
// holds iff shift (= kappa rho_t) is zero; returns the INFEASIBLE message
// when it is not.
std::string AddExactCones(const PreparedProblem& prepared, Formulation* form) {
  const PlanProblem& problem = prepared.problem;
  for (int i = 0; i < prepared.num_contacts(); ++i) {
    const double shift = prepared.cone_shift[static_cast<size_t>(i)];
    if (form->frictionless[i]) {
      if (shift > kFeasibilityTolerance) {
        return ContactLabel(problem, i) +
               " is frictionless but must resist a tangential force uncertainty kappa*rho_t = " +
               FormatNumber(shift) + " N";
      }
      continue;
    }
    ConeConstraint cone;
    cone.contact = i;
    cone.offset = form->offset[i];
    cone.s_index = form->num_forces + static_cast<int>(form->cones.size());
    cone.normal = problem.contacts[static_cast<size_t>(i)].normal;
    cone.mu = problem.contacts[static_cast<size_t>(i)].friction;
    cone.shift = shift;
    Terms terms = {{cone.s_index, 1.0}};
    for (int a = 0; a < 3; ++a) terms.emplace_back(cone.offset + a, -cone.mu * cone.normal(a));
    AddRow(terms, -cone.shift, -cone.shift, {RowOrigin::kConeSlack, i}, form);
    form->cones.push_back(cone);
  }
  return {};
}

// Start: the minimum-norm equilibrium z0, each slack at least |P f| so that
// r <= 0 holds and only linear rows are violated (r = |P f|^2 / s - s
// explodes for small s).
void SetStart(const VectorXd& z0, Formulation* form) {
  form->start = VectorXd::Zero(form->num_vars());
  form->start.head(form->num_forces) = z0;
  for (const ConeConstraint& cone : form->cones) {
    const double* x = form->start.data();
    form->start(cone.s_index) =
        std::max({cone.Radius(x), cone.Tangential(x).norm(), 1e-2 * form->scale});
  }
}

}  // namespace

std::string FormatNumber(double value) {
  std::ostringstream out;
  out.precision(4);
  out << value;
  return out.str();
}

std::vector<Vec3> Formulation::Forces(const VectorXd& z) const {
  std::vector<Vec3> forces(offset.size());
  for (size_t i = 0; i < offset.size(); ++i) {
    forces[i] = frictionless[i] ? Vec3(normal[i] * z(offset[i])) : Vec3(z.segment<3>(offset[i]));
  }
  return forces;
}

VectorXd Formulation::LinearValues(const double* x) const {
  VectorXd values = VectorXd::Zero(num_linear);
  for (const Entry& e : linear) values(e.row) += e.value * x[e.col];
  return values;
}

double Formulation::MaxViolation(const VectorXd& x) const {
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

double Formulation::EquilibriumResidual(const VectorXd& x) const {
  const VectorXd values = LinearValues(x.data());
  double residual = 0.0;
  for (int r = 0; r < num_equilibrium; ++r) {
    residual = std::max(residual, std::abs(values(r) - upper[r]));
  }
  return residual;
}

FormulationOutcome BuildFormulation(const PreparedProblem& prepared, const PlanOptions& options) {
  FormulationOutcome out;
  Formulation& form = out.form;
  const bool reduced = AssignUnknowns(prepared.problem, &form);
  const MatrixXd map = reduced ? ForceMap(form) : MatrixXd();
  const MatrixXd* map_or_null = reduced ? &map : nullptr;
  const EquilibriumInUnknowns eq =
      ReduceEquilibrium(prepared.equilibrium, map_or_null, options.rank_tolerance);
  out.infeasible = eq.infeasible;
  if (!out.infeasible.empty()) return out;
  AddEquilibriumRows(eq, &form);
  out.infeasible = AddPlanRows(prepared, map_or_null, &form);
  if (!out.infeasible.empty()) return out;
  if (options.cone == ConeModel::kExact) {
    out.infeasible = AddExactCones(prepared, &form);
    if (!out.infeasible.empty()) return out;
  }
  form.num_linear = static_cast<int>(form.lower.size());
  SetStart(eq.start, &form);
  return out;
}

}  // namespace tactforce::planner::internal
