// ForceNlp (ipopt_nlp.h): the Ipopt callbacks of one run, and the stop
// conditions they poll.
#include "planner/src/ipopt_nlp.h"

#include <time.h>

#include <algorithm>
#include <utility>

namespace tactforce::planner::internal {

using Eigen::VectorXd;

double ThreadCpuSeconds() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

StopConditions::Reason StopConditions::Check() const {
  if (interrupt != nullptr && *interrupt && (*interrupt)()) return kInterrupted;
  if (limit_seconds > 0.0 && ThreadCpuSeconds() - start_seconds > limit_seconds) {
    return kTimeLimit;
  }
  return kNone;
}

ForceNlp::ForceNlp(const Formulation& form, Phase phase, VectorXd start, const StopConditions& stop)
    : form_(form),
      phase_(phase),
      start_(std::move(start)),
      stop_(stop),
      t_index_(form.num_vars()),
      num_vars_(form.num_vars() + (phase == Phase::kFeasibility ? 1 : 0)),
      linear_(form.linear),
      stall_step_(kStallStep * std::max({1.0, form.scale, start_.cwiseAbs().maxCoeff()})) {
  if (phase_ == Phase::kFeasibility) {
    for (int r = 0; r < form_.num_linear; ++r) {
      if (form_.origin[r].kind != RowOrigin::kEquilibrium) {
        linear_.push_back({r, t_index_, -1.0});
      }
    }
  }
  BuildHessianStructure();
}

// Lower triangle of the Lagrangian Hessian: the diagonal of every force
// unknown (the objective 2 I); for a cone the 3x3 force block, the (s, f)
// row and (s, s).
void ForceNlp::BuildHessianStructure() {
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
      cone_hess_start_[static_cast<size_t>(cone_of[i])] = static_cast<int>(hess_.size());
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

bool ForceNlp::get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                            IndexStyleEnum& index_style) {
  n = num_vars_;
  m = form_.num_constraints();
  nnz_jac_g = static_cast<Index>(linear_.size() + 4 * form_.cones.size());
  nnz_h_lag = static_cast<Index>(hess_.size());
  index_style = C_STYLE;
  return true;
}

bool ForceNlp::get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                               Number* g_u) {
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

bool ForceNlp::get_constraints_linearity(Index m, LinearityType* types) {
  for (Index r = 0; r < m; ++r) types[r] = r < form_.num_linear ? LINEAR : NON_LINEAR;
  return true;
}

bool ForceNlp::get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_L,
                                  Number* z_U, Index m, bool init_lambda, Number* lambda) {
  if (init_z || init_lambda) return false;  // no warm start offered
  if (init_x) {
    for (Index j = 0; j < n; ++j) x[j] = start_(j);
  }
  return true;
}

bool ForceNlp::eval_f(Index n, const Number* x, bool new_x, Number& obj) {
  obj = phase_ == Phase::kFeasibility
            ? x[t_index_]
            : Eigen::Map<const VectorXd>(x, form_.num_forces).squaredNorm();
  return true;
}

bool ForceNlp::eval_grad_f(Index n, const Number* x, bool new_x, Number* grad) {
  for (Index j = 0; j < n; ++j) {
    if (phase_ == Phase::kFeasibility) {
      grad[j] = j == t_index_ ? 1.0 : 0.0;
    } else {
      grad[j] = j < form_.num_forces ? 2.0 * x[j] : 0.0;
    }
  }
  return true;
}

bool ForceNlp::eval_g(Index n, const Number* x, bool new_x, Index m, Number* g) {
  for (Index r = 0; r < m; ++r) g[r] = 0.0;
  for (const Entry& e : linear_) g[e.row] += e.value * x[e.col];
  for (size_t k = 0; k < form_.cones.size(); ++k) {
    if (!(x[form_.cones[k].s_index] > 0.0)) return false;  // outside domain
    g[form_.num_linear + k] = form_.cones[k].Value(x);
  }
  return true;
}

bool ForceNlp::eval_jac_g(Index n, const Number* x, bool new_x, Index m, Index nele_jac,
                          Index* i_row, Index* j_col, Number* values) {
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

bool ForceNlp::eval_h(Index n, const Number* x, bool new_x, Number obj_factor, Index m,
                      const Number* lambda, bool new_lambda, Index nele_hess, Index* i_row,
                      Index* j_col, Number* values) {
  if (values == nullptr) {
    for (size_t e = 0; e < hess_.size(); ++e) {
      i_row[e] = hess_[e].row;
      j_col[e] = hess_[e].col;
    }
    return true;
  }
  const double diagonal = phase_ == Phase::kFeasibility ? 0.0 : 2.0 * obj_factor;
  for (size_t e = 0; e < hess_.size(); ++e) {
    values[e] = hess_[e].row == hess_[e].col && hess_[e].row < form_.num_forces ? diagonal : 0.0;
  }
  for (const ConeConstraint& c : form_.cones) {
    if (!(x[c.s_index] > 0.0)) return false;
  }
  AddConeHessian(x, lambda, values);
  return true;
}

// Adds lambda_k times the Hessian of r_k, every slack s > 0:
// d2r/df2 = 2 P / s, d2r/ds df = -2 P f / s^2, d2r/ds2 = 2 |P f|^2 / s^3.
void ForceNlp::AddConeHessian(const Number* x, const Number* lambda, Number* values) const {
  for (size_t k = 0; k < form_.cones.size(); ++k) {
    const ConeConstraint& c = form_.cones[k];
    const double s = x[c.s_index];
    const double weight = lambda[form_.num_linear + k];
    const Vec3 w = c.Tangential(x);
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - c.normal * c.normal.transpose();
    int e = cone_hess_start_[k];
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b <= a; ++b) values[e++] += weight * 2.0 * p(a, b) / s;
    }
    e = cone_hess_s_start_[k];
    for (int a = 0; a < 3; ++a) values[e++] -= weight * 2.0 * w(a) / (s * s);
    values[e] += weight * 2.0 * w.squaredNorm() / (s * s * s);
  }
}

void ForceNlp::finalize_solution(Ipopt::SolverReturn status, Index n, const Number* x,
                                 const Number* z_L, const Number* z_U, Index m, const Number* g,
                                 const Number* lambda, Number obj_value,
                                 const Ipopt::IpoptData* ip_data,
                                 Ipopt::IpoptCalculatedQuantities* ip_cq) {
  solution_ = Eigen::Map<const VectorXd>(x, n);
}

bool ForceNlp::intermediate_callback(Ipopt::AlgorithmMode mode, Index iter, Number obj_value,
                                     Number inf_pr, Number inf_du, Number mu, Number d_norm,
                                     Number regularization_size, Number alpha_du, Number alpha_pr,
                                     Index ls_trials, const Ipopt::IpoptData* ip_data,
                                     Ipopt::IpoptCalculatedQuantities* ip_cq) {
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

}  // namespace tactforce::planner::internal
