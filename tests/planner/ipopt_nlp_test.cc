// Tests of ForceNlp (planner/src/ipopt_nlp.h), the Ipopt callbacks, called
// directly as Ipopt would: sizes, bounds, sparsity structure, derivatives
// against finite differences, domain checks and the stop/stall logic.
#include "planner/src/ipopt_nlp.h"

#include <cmath>
#include <functional>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "planner/fixtures.h"
#include "planner/src/ipopt_formulation.h"

namespace tactforce::planner::internal {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using Index = Ipopt::Index;
using fixtures::Finger;
using fixtures::Options;
using fixtures::Pinch;
using fixtures::Prepared;
using fixtures::ThreeFingerGrasp;

// A formulation and what to pose it as.
struct Case {
  std::string name;
  Formulation form;
  Phase phase = Phase::kMinimumNorm;
};

Formulation Build(const PlanProblem& problem, const PlanOptions& options) {
  const FormulationOutcome out = BuildFormulation(Prepared(problem, options), options);
  EXPECT_EQ(out.infeasible, "");
  return out.form;
}

// Noisy four-finger grasp (pyramid and exact) and a pinch on a frictionless
// table (exact: two cones and a one-unknown contact), in both phases.
std::vector<Case> Cases() {
  PlanProblem table = Pinch(0.5, 0.5, 2.0);
  Contact support = Finger(Vec3(0, 0, -0.03), Vec3(0, 0, 1), 0.0);
  support.kind = ContactKind::kExtrinsic;
  table.contacts.push_back(support);
  const std::vector<std::pair<std::string, Formulation>> forms = {
      {"pyramid", Build(ThreeFingerGrasp(4, 0.3), Options(ConeModel::kPyramid, 1.0))},
      {"exact", Build(ThreeFingerGrasp(4, 0.3), Options(ConeModel::kExact, 1.0))},
      {"exact+frictionless", Build(table, Options(ConeModel::kExact))},
  };
  std::vector<Case> cases;
  for (const auto& [name, form] : forms) {
    cases.push_back({name + " minimum-norm", form, Phase::kMinimumNorm});
    cases.push_back({name + " phase one", form, Phase::kFeasibility});
  }
  return cases;
}

int NumVars(const Case& c) { return c.form.num_vars() + (c.phase == Phase::kFeasibility ? 1 : 0); }

// The run's start: the formulation's, plus t = 1 in phase one.
VectorXd Start(const Case& c) {
  VectorXd x = VectorXd::Ones(NumVars(c));
  x.head(c.form.num_vars()) = c.form.start;
  return x;
}

// Forces in [-5, 5] N; slacks and t in [0.5, 3] (inside r's domain).
VectorXd RandomPoint(const Case& c, std::mt19937& rng) {
  std::uniform_real_distribution<double> force(-5.0, 5.0), slack(0.5, 3.0);
  VectorXd x(NumVars(c));
  for (int j = 0; j < x.size(); ++j) x(j) = j < c.form.num_forces ? force(rng) : slack(rng);
  return x;
}

struct Sizes {
  Index n = 0, m = 0, nnz_jac = 0, nnz_hess = 0;
};

Sizes GetSizes(ForceNlp& nlp) {
  Sizes s;
  Ipopt::TNLP::IndexStyleEnum style;
  EXPECT_TRUE(nlp.get_nlp_info(s.n, s.m, s.nnz_jac, s.nnz_hess, style));
  EXPECT_EQ(style, Ipopt::TNLP::C_STYLE);
  return s;
}

// (row, col) pairs of the Jacobian (hessian = false) or Hessian structure.
std::vector<std::pair<Index, Index>> Structure(ForceNlp& nlp, bool hessian) {
  const Sizes s = GetSizes(nlp);
  const Index nnz = hessian ? s.nnz_hess : s.nnz_jac;
  std::vector<Index> rows(nnz), cols(nnz);
  const VectorXd x = VectorXd::Ones(s.n);
  EXPECT_TRUE(
      hessian ? nlp.eval_h(s.n, x.data(), true, 1.0, s.m, nullptr, true, nnz, rows.data(),
                           cols.data(), nullptr)
              : nlp.eval_jac_g(s.n, x.data(), true, s.m, nnz, rows.data(), cols.data(), nullptr));
  std::vector<std::pair<Index, Index>> out;
  for (Index e = 0; e < nnz; ++e) out.emplace_back(rows[e], cols[e]);
  return out;
}

double Objective(ForceNlp& nlp, const VectorXd& x) {
  double f = 0.0;
  EXPECT_TRUE(nlp.eval_f(static_cast<Index>(x.size()), x.data(), true, f));
  return f;
}

VectorXd Gradient(ForceNlp& nlp, const VectorXd& x) {
  VectorXd g(x.size());
  EXPECT_TRUE(nlp.eval_grad_f(static_cast<Index>(x.size()), x.data(), true, g.data()));
  return g;
}

VectorXd Constraints(ForceNlp& nlp, const VectorXd& x) {
  const Sizes s = GetSizes(nlp);
  VectorXd g(s.m);
  EXPECT_TRUE(nlp.eval_g(s.n, x.data(), true, s.m, g.data()));
  return g;
}

MatrixXd Jacobian(ForceNlp& nlp, const VectorXd& x) {
  const Sizes s = GetSizes(nlp);
  const auto structure = Structure(nlp, /*hessian=*/false);
  VectorXd values(s.nnz_jac);
  EXPECT_TRUE(nlp.eval_jac_g(s.n, x.data(), true, s.m, s.nnz_jac, nullptr, nullptr, values.data()));
  MatrixXd j = MatrixXd::Zero(s.m, s.n);
  for (Index e = 0; e < s.nnz_jac; ++e) j(structure[e].first, structure[e].second) += values(e);
  return j;
}

// The full symmetric Hessian of obj_factor f + lambda^T g from its lower triangle.
MatrixXd Hessian(ForceNlp& nlp, const VectorXd& x, double obj_factor, const VectorXd& lambda) {
  const Sizes s = GetSizes(nlp);
  const auto structure = Structure(nlp, /*hessian=*/true);
  VectorXd values(s.nnz_hess);
  EXPECT_TRUE(nlp.eval_h(s.n, x.data(), true, obj_factor, s.m, lambda.data(), true, s.nnz_hess,
                         nullptr, nullptr, values.data()));
  MatrixXd h = MatrixXd::Zero(s.n, s.n);
  for (Index e = 0; e < s.nnz_hess; ++e) {
    const auto [r, c] = structure[e];
    h(r, c) += values(e);
    if (r != c) h(c, r) += values(e);
  }
  return h;
}

// Central differences of a vector function, one column per unknown.
MatrixXd FiniteDifferences(const std::function<VectorXd(const VectorXd&)>& fn, const VectorXd& x) {
  const VectorXd f0 = fn(x);
  MatrixXd d(f0.size(), x.size());
  for (int j = 0; j < x.size(); ++j) {
    const double h = 1e-6 * std::max(1.0, std::abs(x(j)));
    VectorXd plus = x, minus = x;
    plus(j) += h;
    minus(j) -= h;
    d.col(j) = (fn(plus) - fn(minus)) / (2.0 * h);
  }
  return d;
}

// Largest |a - b| relative to 1 + |a|, entrywise.
double MaxRelativeError(const MatrixXd& a, const MatrixXd& b) {
  return ((a - b).cwiseAbs().array() / (1.0 + a.cwiseAbs().array())).maxCoeff();
}

TEST(IpoptNlp, SizesFollowTheFormulation) {
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
    const Sizes s = GetSizes(nlp);
    const int cones = static_cast<int>(c.form.cones.size());
    EXPECT_EQ(s.n, NumVars(c));
    EXPECT_EQ(nlp.num_vars(), s.n);
    EXPECT_EQ(s.m, c.form.num_linear + cones);
    // Phase one adds -t to every row but the equilibrium rows.
    const int relaxed =
        c.phase == Phase::kFeasibility ? c.form.num_linear - c.form.num_equilibrium : 0;
    EXPECT_EQ(s.nnz_jac, static_cast<Index>(c.form.linear.size()) + 4 * cones + relaxed);
    // Hessian: one diagonal entry per force unknown outside a cone; per cone
    // the 3x3 lower triangle (6), the (s, f) row (3) and (s, s).
    int expected_hess = 0;
    for (size_t i = 0; i < c.form.offset.size(); ++i) {
      expected_hess += c.form.frictionless[i] ? 1 : 3;
    }
    expected_hess += cones * (6 - 3 + 4);
    EXPECT_EQ(s.nnz_hess, expected_hess);
  }
}

TEST(IpoptNlp, StructuresAreInRangeWithoutRepeatsAndTheHessianIsLowerTriangular) {
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
    const Sizes s = GetSizes(nlp);
    for (bool hessian : {false, true}) {
      const auto structure = Structure(nlp, hessian);
      const std::set<std::pair<Index, Index>> unique(structure.begin(), structure.end());
      EXPECT_EQ(unique.size(), structure.size()) << (hessian ? "Hessian" : "Jacobian");
      for (const auto& [row, col] : structure) {
        EXPECT_GE(row, 0);
        EXPECT_LT(row, hessian ? s.n : s.m);
        EXPECT_GE(col, 0);
        EXPECT_LT(col, s.n);
        if (hessian) {
          EXPECT_GE(row, col);
        }
      }
    }
  }
}

TEST(IpoptNlp, BoundsAndLinearityFollowTheFormulation) {
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
    const Sizes s = GetSizes(nlp);
    VectorXd x_l(s.n), x_u(s.n), g_l(s.m), g_u(s.m);
    ASSERT_TRUE(nlp.get_bounds_info(s.n, x_l.data(), x_u.data(), s.m, g_l.data(), g_u.data()));
    for (Index j = 0; j < s.n; ++j) {
      // Forces free; cone slacks s >= 0 and phase one's t >= 0.
      EXPECT_EQ(x_l(j), j < c.form.num_forces ? -kInfinity : 0.0) << j;
      EXPECT_EQ(x_u(j), kInfinity) << j;
    }
    std::vector<Ipopt::TNLP::LinearityType> types(s.m);
    ASSERT_TRUE(nlp.get_constraints_linearity(s.m, types.data()));
    for (Index r = 0; r < s.m; ++r) {
      const bool linear = r < c.form.num_linear;
      EXPECT_EQ(g_l(r), linear ? c.form.lower[r] : -kInfinity) << r;
      EXPECT_EQ(g_u(r), linear ? c.form.upper[r] : 0.0) << r;
      EXPECT_EQ(types[r], linear ? Ipopt::TNLP::LINEAR : Ipopt::TNLP::NON_LINEAR) << r;
    }
  }
}

TEST(IpoptNlp, ObjectiveIsTheSquaredForceNormOrTheRelaxation) {
  std::mt19937 rng(3);
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
    const VectorXd x = RandomPoint(c, rng);
    const double expected = c.phase == Phase::kFeasibility
                                ? x(c.form.num_vars())
                                : x.head(c.form.num_forces).squaredNorm();
    EXPECT_DOUBLE_EQ(Objective(nlp, x), expected);
  }
}

TEST(IpoptNlp, DerivativesMatchFiniteDifferences) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> multiplier(-2.0, 2.0);
  for (const Case& c : Cases()) {
    SCOPED_TRACE(c.name);
    ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
    const Sizes s = GetSizes(nlp);
    for (int trial = 0; trial < 5; ++trial) {
      const VectorXd x = RandomPoint(c, rng);
      const MatrixXd grad_fd = FiniteDifferences(
          [&](const VectorXd& y) { return VectorXd::Constant(1, Objective(nlp, y)); }, x);
      EXPECT_LE(MaxRelativeError(Gradient(nlp, x).transpose(), grad_fd), 1e-6);
      const MatrixXd jac_fd =
          FiniteDifferences([&](const VectorXd& y) { return Constraints(nlp, y); }, x);
      EXPECT_LE(MaxRelativeError(Jacobian(nlp, x), jac_fd), 1e-6);
      // Hessian of the Lagrangian: differences of its analytic gradient.
      const double obj_factor = 0.7;
      VectorXd lambda(s.m);
      for (Index r = 0; r < s.m; ++r) lambda(r) = multiplier(rng);
      const MatrixXd hess_fd = FiniteDifferences(
          [&](const VectorXd& y) -> VectorXd {
            return obj_factor * Gradient(nlp, y) + Jacobian(nlp, y).transpose() * lambda;
          },
          x);
      EXPECT_LE(MaxRelativeError(Hessian(nlp, x, obj_factor, lambda), hess_fd), 1e-6);
    }
  }
}

TEST(IpoptNlp, PhaseOneRelaxesEveryInequalityRowByT) {
  const Case c = Cases()[3];  // exact, phase one
  ASSERT_EQ(c.phase, Phase::kFeasibility);
  ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
  std::mt19937 rng(9);
  const VectorXd x = RandomPoint(c, rng);
  const MatrixXd j = Jacobian(nlp, x);
  const int t = c.form.num_vars();
  for (int r = 0; r < c.form.num_linear; ++r) {
    EXPECT_EQ(j(r, t), c.form.origin[r].kind == RowOrigin::kEquilibrium ? 0.0 : -1.0) << r;
  }
  for (int r = c.form.num_linear; r < j.rows(); ++r) EXPECT_EQ(j(r, t), 0.0) << r;
  EXPECT_EQ(Gradient(nlp, x), VectorXd::Unit(x.size(), t));
}

TEST(IpoptNlp, EvaluationsOutsideTheConeDomainFail) {
  const Case c = Cases()[2];  // exact, minimum norm
  ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
  const Sizes s = GetSizes(nlp);
  VectorXd x = Start(c);
  x(c.form.cones[1].s_index) = 0.0;
  VectorXd g(s.m), jac(s.nnz_jac), hess(s.nnz_hess), lambda = VectorXd::Ones(s.m);
  EXPECT_FALSE(nlp.eval_g(s.n, x.data(), true, s.m, g.data()));
  EXPECT_FALSE(nlp.eval_jac_g(s.n, x.data(), true, s.m, s.nnz_jac, nullptr, nullptr, jac.data()));
  EXPECT_FALSE(nlp.eval_h(s.n, x.data(), true, 1.0, s.m, lambda.data(), true, s.nnz_hess, nullptr,
                          nullptr, hess.data()));
  // The objective does not depend on the slacks and is still defined.
  double f = 0.0;
  EXPECT_TRUE(nlp.eval_f(s.n, x.data(), true, f));
}

TEST(IpoptNlp, StartsAtTheGivenPointWithoutAWarmStart) {
  const Case c = Cases()[1];  // pyramid, phase one
  const VectorXd start = Start(c);
  ForceNlp nlp(c.form, c.phase, start, StopConditions{});
  const Sizes s = GetSizes(nlp);
  VectorXd x = VectorXd::Zero(s.n), z(s.n), lambda(s.m);
  ASSERT_TRUE(
      nlp.get_starting_point(s.n, true, x.data(), false, nullptr, nullptr, s.m, false, nullptr));
  EXPECT_EQ(x, start);
  EXPECT_FALSE(
      nlp.get_starting_point(s.n, true, x.data(), true, z.data(), z.data(), s.m, false, nullptr));
  EXPECT_FALSE(nlp.get_starting_point(s.n, true, x.data(), false, nullptr, nullptr, s.m, true,
                                      lambda.data()));
  const VectorXd solution = VectorXd::LinSpaced(s.n, -1.0, 1.0);
  nlp.finalize_solution(Ipopt::SUCCESS, s.n, solution.data(), nullptr, nullptr, s.m, nullptr,
                        nullptr, 0.0, nullptr, nullptr);
  EXPECT_EQ(nlp.solution(), solution);
}

// What Ipopt's intermediate_callback passes that matters here.
bool Iterate(ForceNlp& nlp, Index iter, double mu, double d_norm,
             Ipopt::AlgorithmMode mode = Ipopt::RegularMode) {
  return nlp.intermediate_callback(mode, iter, 0.0, 0.0, 0.0, mu, d_norm, 0.0, 1.0, 1.0, 0, nullptr,
                                   nullptr);
}

TEST(IpoptNlp, StopsAfterStalledIterations) {
  const Case c = Cases()[2];
  for (Ipopt::AlgorithmMode mode : {Ipopt::RegularMode, Ipopt::RestorationPhaseMode}) {
    ForceNlp nlp(c.form, c.phase, Start(c), StopConditions{});
    EXPECT_TRUE(Iterate(nlp, 0, 0.1, 0.0, mode));  // iteration 0 takes no step
    Index iter = 1;
    for (; iter < kStallIterations; ++iter) EXPECT_TRUE(Iterate(nlp, iter, 0.1, 0.0, mode));
    EXPECT_TRUE(Iterate(nlp, iter++, 0.1, 1.0, mode));  // a real step resets the count
    for (int k = 1; k < kStallIterations; ++k) EXPECT_TRUE(Iterate(nlp, iter++, 1e-3, 0.0, mode));
    EXPECT_FALSE(nlp.stalled());
    EXPECT_FALSE(Iterate(nlp, iter, 1e-9, 0.0, mode));
    EXPECT_TRUE(nlp.stalled());
    EXPECT_EQ(nlp.stalled_in_restoration(), mode == Ipopt::RestorationPhaseMode);
    EXPECT_EQ(nlp.stop_reason(), StopConditions::kNone);
    EXPECT_EQ(nlp.last_iteration(), iter);
    EXPECT_EQ(nlp.last_mu(), 1e-9);
  }
}

TEST(IpoptNlp, StopsWhenInterruptedOrOutOfTime) {
  const Case c = Cases()[0];
  int polls = 0;
  const std::function<bool()> interrupt = [&polls] { return ++polls >= 2; };
  ForceNlp interrupted(c.form, c.phase, Start(c), StopConditions{0.0, 0.0, &interrupt});
  EXPECT_TRUE(Iterate(interrupted, 0, 0.1, 1.0));
  EXPECT_FALSE(Iterate(interrupted, 1, 0.1, 1.0));
  EXPECT_EQ(interrupted.stop_reason(), StopConditions::kInterrupted);
  EXPECT_FALSE(interrupted.stalled());

  const std::function<bool()> empty;
  const StopConditions out_of_time{1e-3, ThreadCpuSeconds() - 1.0, &empty};
  EXPECT_EQ(out_of_time.Check(), StopConditions::kTimeLimit);
  ForceNlp timed(c.form, c.phase, Start(c), out_of_time);
  EXPECT_FALSE(Iterate(timed, 0, 0.1, 1.0));
  EXPECT_EQ(timed.stop_reason(), StopConditions::kTimeLimit);

  const StopConditions generous{100.0, ThreadCpuSeconds(), &empty};
  EXPECT_EQ(generous.Check(), StopConditions::kNone);
  EXPECT_EQ(StopConditions{}.Check(), StopConditions::kNone);
}

}  // namespace
}  // namespace tactforce::planner::internal
