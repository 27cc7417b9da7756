// Internal to the Ipopt backend: ForceNlp, the Ipopt::TNLP that poses a
// Formulation (ipopt_formulation.h) to Ipopt, with exact first and second
// derivatives, and the stop conditions polled between its iterations.
// Exposed (like Drake's ipopt_solver_internal.h) so that it can be tested
// without running Ipopt.
//
// EXACT cones are posed as r(f, s) = |P f|^2 / s - s <= 0 with s >= 0 (i.e.
// |P f| <= s). Why not |P f|^2 - s^2 <= 0 with a linear row s >= 0: its
// gradient vanishes at the cone apex, which is where the minimum-norm plan
// puts every contact it does not need; there Ipopt took ~850 iterations and
// left 1e-4 N of tangential force on a contact that should carry none (a
// violation eps of the squared form admits sqrt(eps) of force). A smoothed
// sqrt(|P f|^2 + eps^2) - eps <= s behaves like |P f| for small eps and made
// Ipopt oscillate (400+ iterations at eps = 1e-4 N). r keeps a non-zero
// gradient (dr/ds <= -1) and measures violations in N. Its one weakness: at
// an apex (s = 0, P f = 0) the bound s >= 0 and r are both active with
// parallel gradients, so the multipliers are not unique. Ipopt then
// sometimes keeps iterating with a vanishing primal step and a dual
// infeasibility that cannot reach tol; ForceNlp stops such a run after
// kStallIterations (stalled()), and the driver judges the point.
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "IpTNLP.hpp"
#include "planner/src/ipopt_formulation.h"

namespace tactforce::planner::internal {

// A run has stalled when the primal step stays below kStallStep times the
// size of the unknowns for kStallIterations iterations in a row.
inline constexpr double kStallStep = 1e-12;
inline constexpr int kStallIterations = 8;

// CPU time (s) of the calling thread (CLOCK_THREAD_CPUTIME_ID).
double ThreadCpuSeconds();

// Why a solve must stop early; shared by the Ipopt runs of one solve.
struct StopConditions {
  double limit_seconds = 0.0;  // thread CPU budget (s); <= 0: none
  double start_seconds = 0.0;  // ThreadCpuSeconds() at the start of the solve
  const std::function<bool()>* interrupt =
      nullptr;  // SolveControl::interrupt; may be null or empty

  enum Reason { kNone, kTimeLimit, kInterrupted };
  // The interrupt is polled first; then the budget.
  Reason Check() const;
};

// Which problem the TNLP poses.
enum class Phase {
  // min |z|^2 subject to everything: the answer.
  kMinimumNorm,
  // min t >= 0 with every inequality relaxed by t (rows a.f <= d + t, cone
  // slacks s = s(f) + t); the equilibrium stays exact. Always feasible;
  // t* > 0 proves the problem infeasible. t is the last unknown.
  kFeasibility,
};

// The TNLP handed to Ipopt. Owned by one run; not shared. `form` must
// outlive it. Unknowns: form's (z, s), plus t in phase one; constraints:
// form's linear rows (in phase one every non-equilibrium row gets -t), then
// one r_i <= 0 per cone. Evaluations at a point with a slack s <= 0 (outside
// r's domain) return false. Hessian: lower triangle, a fixed structure.
class ForceNlp final : public Ipopt::TNLP {
 public:
  using Index = Ipopt::Index;
  using Number = Ipopt::Number;

  // `start` has num_vars() entries (form.num_vars(), + 1 in phase one).
  ForceNlp(const Formulation& form, Phase phase, Eigen::VectorXd start, const StopConditions& stop);

  int num_vars() const { return num_vars_; }

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override;
  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                       Number* g_u) override;
  bool get_constraints_linearity(Index m, LinearityType* types) override;
  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_L, Number* z_U,
                          Index m, bool init_lambda, Number* lambda) override;
  bool eval_f(Index n, const Number* x, bool new_x, Number& obj) override;
  bool eval_grad_f(Index n, const Number* x, bool new_x, Number* grad) override;
  bool eval_g(Index n, const Number* x, bool new_x, Index m, Number* g) override;
  bool eval_jac_g(Index n, const Number* x, bool new_x, Index m, Index nele_jac, Index* i_row,
                  Index* j_col, Number* values) override;
  bool eval_h(Index n, const Number* x, bool new_x, Number obj_factor, Index m,
              const Number* lambda, bool new_lambda, Index nele_hess, Index* i_row, Index* j_col,
              Number* values) override;
  void finalize_solution(Ipopt::SolverReturn status, Index n, const Number* x, const Number* z_L,
                         const Number* z_U, Index m, const Number* g, const Number* lambda,
                         Number obj_value, const Ipopt::IpoptData* ip_data,
                         Ipopt::IpoptCalculatedQuantities* ip_cq) override;
  // Records the iteration and barrier parameter; returns false (stop) when
  // `stop` says so or the run has stalled.
  bool intermediate_callback(Ipopt::AlgorithmMode mode, Index iter, Number obj_value, Number inf_pr,
                             Number inf_du, Number mu, Number d_norm, Number regularization_size,
                             Number alpha_du, Number alpha_pr, Index ls_trials,
                             const Ipopt::IpoptData* ip_data,
                             Ipopt::IpoptCalculatedQuantities* ip_cq) override;

  // After the run.
  const Eigen::VectorXd& solution() const { return solution_; }  // empty if none
  StopConditions::Reason stop_reason() const { return stop_reason_; }
  int last_iteration() const { return last_iteration_; }
  double last_mu() const { return last_mu_; }
  bool stalled() const { return stalled_; }
  bool stalled_in_restoration() const { return stalled_in_restoration_; }

 private:
  void BuildHessianStructure();
  void AddConeHessian(const Number* x, const Number* lambda, Number* values) const;

  const Formulation& form_;
  const Phase phase_;
  const Eigen::VectorXd start_;
  const StopConditions stop_;
  const int t_index_;  // the relaxation t (phase one only)
  const int num_vars_;
  std::vector<Entry> linear_;           // L, with the t column in phase one
  std::vector<Entry> hess_;             // structure of the Hessian
  std::vector<int> cone_hess_start_;    // 3x3 force block, per cone
  std::vector<int> cone_hess_s_start_;  // (s, f) row and (s, s), per cone
  const double stall_step_;             // primal steps below this count as stalled
  Eigen::VectorXd solution_;
  StopConditions::Reason stop_reason_ = StopConditions::kNone;
  int last_iteration_ = 0;
  double last_mu_ = 0.0;
  int stall_count_ = 0;
  bool stalled_ = false;
  bool stalled_in_restoration_ = false;
};

}  // namespace tactforce::planner::internal
