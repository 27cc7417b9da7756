// Tests of the Ipopt backend's NLP data (planner/src/ipopt_formulation.h),
// built from prepared problems without running Ipopt.
#include "planner/src/ipopt_formulation.h"

#include <algorithm>
#include <cmath>
#include <random>
#include <string>
#include <utility>

#include <Eigen/SVD>
#include <gtest/gtest.h>

#include "planner/fixtures.h"
#include "tactforce/planner/solver.h"

namespace tactforce::planner::internal {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using fixtures::Finger;
using fixtures::Options;
using fixtures::Pinch;
using fixtures::Prepared;
using fixtures::ThreeFingerGrasp;

// The pinch standing on a frictionless table (contact 2) under the centre of mass.
PlanProblem PinchOnATable(double sigma) {
  PlanProblem p = Pinch(0.5, 0.5, 2.0);
  for (Contact& c : p.contacts) c.sigma = sigma;
  Contact table = Finger(Vec3(0.01, 0.004, -0.03), Vec3(0.1, 0, 1).normalized(), 0.0);
  table.name = "table";
  table.kind = ContactKind::kExtrinsic;
  p.contacts.push_back(table);
  return p;
}

// L as a dense matrix (num_linear x num_vars).
MatrixXd DenseLinear(const Formulation& form) {
  MatrixXd l = MatrixXd::Zero(form.num_linear, form.num_vars());
  for (const Entry& e : form.linear) l(e.row, e.col) += e.value;
  return l;
}

VectorXd Stack(const std::vector<Vec3>& forces) {
  VectorXd f(3 * forces.size());
  for (size_t i = 0; i < forces.size(); ++i) f.segment<3>(3 * i) = forces[i];
  return f;
}

// A prepared problem and the formulation built from it, which must build.
struct Built {
  PreparedProblem prepared;
  Formulation form;
};

Built BuildFeasible(const PlanProblem& problem, const PlanOptions& options) {
  Built built{Prepared(problem, options), {}};
  FormulationOutcome out = BuildFormulation(built.prepared, options);
  EXPECT_EQ(out.infeasible, "");
  built.form = std::move(out.form);
  return built;
}

TEST(IpoptFormulation, FullForceSpaceKeepsEveryRowAndStartsAtTheMinimumNormEquilibrium) {
  const PlanOptions o = Options(ConeModel::kPyramid, 1.0);
  const auto [prepared, form] = BuildFeasible(ThreeFingerGrasp(4, 0.3), o);
  EXPECT_EQ(form.num_forces, 12);
  EXPECT_EQ(form.num_vars(), 12);
  EXPECT_TRUE(form.cones.empty());
  EXPECT_EQ(form.num_equilibrium, prepared.equilibrium.rank);
  const int plan_rows = static_cast<int>(prepared.rows.directions.rows());
  ASSERT_EQ(form.num_linear, form.num_equilibrium + plan_rows);
  EXPECT_EQ(form.num_constraints(), form.num_linear);

  // L is [U_r^T G; A] with bounds [U_r^T b, U_r^T b] and (-inf, d].
  const MatrixXd l = DenseLinear(form);
  const int ne = form.num_equilibrium;
  EXPECT_LE((l.topRows(ne) - prepared.equilibrium.independent_rows).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE((l.bottomRows(plan_rows) - prepared.rows.Dense(prepared.num_contacts()))
                .cwiseAbs()
                .maxCoeff(),
            0.0);
  double scale = 1.0;
  for (int r = 0; r < form.num_linear; ++r) {
    if (r < ne) {
      EXPECT_EQ(form.origin[r].kind, RowOrigin::kEquilibrium);
      EXPECT_EQ(form.lower[r], prepared.equilibrium.independent_rhs(r));
      EXPECT_EQ(form.upper[r], form.lower[r]);
      scale = std::max(scale, std::abs(form.upper[r]));
    } else {
      EXPECT_EQ(form.origin[r].kind, RowOrigin::kPlanRow);
      EXPECT_EQ(form.origin[r].index, r - ne);
      EXPECT_LE(form.lower[r], -kInfinity);
      EXPECT_EQ(form.upper[r], prepared.rows.rhs(r - ne));
      scale = std::max(scale, std::abs(form.upper[r]));
    }
  }
  EXPECT_EQ(form.scale, scale);
  EXPECT_LE((form.start - prepared.equilibrium.particular).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_LE(form.EquilibriumResidual(form.start), 1e-12);
}

TEST(IpoptFormulation, ExactConesGetASlackUnknownAndThePreparedShift) {
  const PlanOptions o = Options(ConeModel::kExact, 2.0);
  const auto [prepared, form] = BuildFeasible(ThreeFingerGrasp(4, 0.3), o);
  ASSERT_EQ(form.cones.size(), 4u);
  EXPECT_EQ(form.num_vars(), 16);
  EXPECT_EQ(form.num_constraints(), form.num_linear + 4);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> force(-5.0, 5.0);
  for (int k = 0; k < 4; ++k) {
    const ConeConstraint& cone = form.cones[k];
    const Contact& c = prepared.problem.contacts[k];
    EXPECT_EQ(cone.contact, k);
    EXPECT_EQ(cone.offset, 3 * k);
    EXPECT_EQ(cone.s_index, 12 + k);
    EXPECT_EQ(cone.mu, c.friction);
    EXPECT_EQ(cone.shift, prepared.cone_shift[k]);
    EXPECT_GT(cone.shift, 0.0);
    // Its row: s - mu n.f = -shift, so s = Radius(f) satisfies it.
    const auto row = std::find_if(form.origin.begin(), form.origin.end(), [&](const RowOrigin& o) {
      return o.kind == RowOrigin::kConeSlack && o.index == k;
    });
    ASSERT_NE(row, form.origin.end());
    const int r = static_cast<int>(row - form.origin.begin());
    EXPECT_EQ(form.lower[r], -cone.shift);
    EXPECT_EQ(form.upper[r], -cone.shift);
    VectorXd x(form.num_vars());
    for (int j = 0; j < x.size(); ++j) x(j) = force(rng);
    x(cone.s_index) = cone.Radius(x.data());
    EXPECT_NEAR(form.LinearValues(x.data())(r), -cone.shift, 1e-12);
    // The start is inside r's domain with r <= 0.
    EXPECT_GT(form.start(cone.s_index), 0.0);
    EXPECT_LE(cone.Value(form.start.data()), 1e-12);
  }
}

TEST(IpoptFormulation, FrictionlessContactHasOneUnknownAlongItsNormal) {
  const PlanOptions o = Options(ConeModel::kPyramid, 0.0);
  const auto [prepared, form] = BuildFeasible(PinchOnATable(0.0), o);
  EXPECT_EQ(form.num_forces, 7);
  EXPECT_EQ(form.offset, (std::vector<int>{0, 3, 6}));
  EXPECT_EQ(form.frictionless, (std::vector<bool>{false, false, true}));
  const VectorXd z = VectorXd::LinSpaced(7, -3.0, 3.0);
  const std::vector<Vec3> forces = form.Forces(z);
  EXPECT_EQ(forces[1], Vec3(z.segment<3>(3)));
  EXPECT_LE((forces[2] - z(6) * prepared.problem.contacts[2].normal).norm(), 1e-15);

  // Equilibrium rows re-reduced to full row rank in z; the start balances.
  const MatrixXd eq_rows = DenseLinear(form).topRows(form.num_equilibrium);
  Eigen::JacobiSVD<MatrixXd> svd(eq_rows);
  EXPECT_GT(svd.singularValues().minCoeff(), 1e-6 * svd.singularValues().maxCoeff());
  const ForceEquilibrium& eq = prepared.equilibrium;
  const VectorXd f = Stack(form.Forces(form.start));
  EXPECT_LE((eq.grasp_matrix * f - eq.wrench).cwiseAbs().maxCoeff(), 1e-10);

  // The table's facets have no unknown left: no row for them.
  const int plan_rows = form.num_linear - form.num_equilibrium;
  EXPECT_EQ(plan_rows, prepared.rows.directions.rows() - o.cone_sides);
  for (int r = form.num_equilibrium; r < form.num_linear; ++r) {
    const RowInfo& info = prepared.rows.info[form.origin[r].index];
    EXPECT_FALSE(info.contact == 2 && info.kind == RowKind::kFrictionFacet) << r;
  }
}

// Noise on the fingers leaves the table an uncertain tangential force that
// no frictionless contact can resist: decided while building.
TEST(IpoptFormulation, UncertainFrictionlessContactIsInfeasible) {
  for (ConeModel cone : {ConeModel::kExact, ConeModel::kPyramid}) {
    const PlanOptions o = Options(cone, 1.0);
    const PreparedProblem prepared = Prepared(PinchOnATable(0.5), o);
    ASSERT_GT(prepared.tangential_sigma[2], 1e-3);
    const FormulationOutcome out = BuildFormulation(prepared, o);
    if (cone == ConeModel::kExact) {
      EXPECT_NE(out.infeasible.find("contact 2 (table) is frictionless"), std::string::npos)
          << out.infeasible;
    } else {
      EXPECT_NE(out.infeasible.find("contact 2 (table) friction cone facet"), std::string::npos)
          << out.infeasible;
    }
  }
  // Without noise both build.
  for (ConeModel cone : {ConeModel::kExact, ConeModel::kPyramid}) {
    const PlanOptions o = Options(cone, 1.0);
    EXPECT_EQ(BuildFormulation(Prepared(PinchOnATable(0.0), o), o).infeasible, "");
  }
}

TEST(IpoptFormulation, FrictionlessPinchCannotBalanceAlongItsNormals) {
  const PlanOptions o = Options(ConeModel::kPyramid);
  const PreparedProblem prepared = Prepared(Pinch(0.5, 0.0), o);
  ASSERT_TRUE(prepared.equilibrium.consistent);  // in the full force space it can
  const FormulationOutcome out = BuildFormulation(prepared, o);
  EXPECT_NE(out.infeasible.find("pushing only along their normals"), std::string::npos)
      << out.infeasible;
}

// MaxViolation is the largest excess of A f over d and of |P f| over
// mu n.f - shift, in N, whatever the slacks; 0 at the Ipopt plan.
TEST(IpoptFormulation, ViolationsAreMeasuredInNewtons) {
  const PlanProblem problem = ThreeFingerGrasp(4, 0.3);
  const PlanOptions o = Options(ConeModel::kExact, 1.0);
  const auto [prepared, form] = BuildFeasible(problem, o);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> value(-4.0, 4.0);
  for (int trial = 0; trial < 20; ++trial) {
    VectorXd x(form.num_vars());
    for (int j = 0; j < x.size(); ++j) x(j) = value(rng);
    const std::vector<Vec3> forces = form.Forces(x.head(form.num_forces));
    double expected = std::max(
        0.0, (prepared.rows.Dense(prepared.num_contacts()) * Stack(forces) - prepared.rows.rhs)
                 .maxCoeff());
    for (int i = 0; i < 4; ++i) {
      const Contact& c = prepared.problem.contacts[i];
      const Vec3 tangential = forces[i] - c.normal.dot(forces[i]) * c.normal;
      expected = std::max(expected, tangential.norm() - (c.friction * c.normal.dot(forces[i]) -
                                                         prepared.cone_shift[i]));
    }
    EXPECT_NEAR(form.MaxViolation(x), expected, 1e-12);
  }
  const absl::StatusOr<PlanResult> plan = MakeSolver(SolverKind::kIpopt)->Solve(problem, o);
  ASSERT_TRUE(plan.ok() && plan->status == PlanStatus::kOptimal);
  VectorXd x = VectorXd::Zero(form.num_vars());
  x.head(form.num_forces) = Stack(plan->forces);
  EXPECT_LE(form.MaxViolation(x), 1e-7);
  EXPECT_LE(form.EquilibriumResidual(x), 1e-8);
  x(0) += 1.0;  // 1 N more along x on contact 0 unbalances the object by 1 N
  EXPECT_GT(form.EquilibriumResidual(x), 1e-3);
}

}  // namespace
}  // namespace tactforce::planner::internal
