// Goldfarb-Idnani dual active-set method (Math. Programming 27, 1983).
//
// Constraints are kept in the form a^T x <= b. The method starts at the
// unconstrained minimum and adds violated constraints one at a time while
// keeping the dual feasible; it maintains J = L^-T Q and the upper
// triangular R of the QR factorisation of L^-1 N_active (H = L L^T), so each
// step costs O(n^2).
#include "tactforce/planner/dense_qp.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#include <Eigen/Cholesky>

namespace tactforce::planner {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kInf = std::numeric_limits<double>::infinity();

// Rotation (c, s) with [c s; -s c] [a; b] = [h; 0].
void Givens(double a, double b, double* c, double* s, double* h) {
  *h = std::hypot(a, b);
  if (*h == 0.0) {
    *c = 1.0;
    *s = 0.0;
  } else {
    *c = a / *h;
    *s = b / *h;
  }
}

class ActiveSetSolver {
 public:
  ActiveSetSolver(const DenseQp& qp, const DenseQpSettings& settings)
      : qp_(qp), settings_(settings), n_(static_cast<int>(qp.gradient.size())),
        p_(static_cast<int>(qp.eq_matrix.rows())), m_(static_cast<int>(qp.in_matrix.rows())) {}

  DenseQpResult Run();

 private:
  // Constraint k of the stacked set (equalities first, then inequalities),
  // as a contiguous column of normals_.
  auto Normal(int k) const { return normals_.col(k); }
  double Rhs(int k) const { return rhs_(k); }
  double Slack(int k) const { return rhs_(k) - normals_.col(k).dot(x_); }
  double Scale(int k) const {
    return std::max({1.0, std::abs(rhs_(k)), normal_norms_(k) * x_.norm()});
  }
  // Normals, right-hand sides, the factorisation J = L^-T and the
  // unconstrained minimum; false if H is not positive definite.
  bool Initialize();
  // Makes every equality active; returns the first inconsistent one, or -1.
  int AddEqualities();
  // Adds inequality k (stacked index), dropping blocking constraints on the
  // way; nullopt once added, else why the solve ends.
  std::optional<DenseQpStatus> AddInequality(int k, int max_iterations);
  // Active inequality limiting the partial step (its position in active_, or
  // -1) and that step length (infinite if none).
  int BlockingActive(double* step) const;
  // Direction in primal (z) and dual (r) spaces for adding constraint k.
  void Directions(int k);
  void AddToFactorization();
  void DropFromFactorization(int position);
  int MostViolated() const;
  DenseQpResult Finish(DenseQpStatus status, int blocking);

  const DenseQp& qp_;
  const DenseQpSettings& settings_;
  const int n_, p_, m_;
  MatrixXd normals_;  // n x (p + m): constraint normals as columns
  VectorXd rhs_, normal_norms_;

  VectorXd x_;
  MatrixXd J_;  // n x n
  MatrixXd R_;  // n x n, upper triangular in its leading q x q block
  VectorXd d_, z_, r_;
  std::vector<int> active_;  // stacked indices, in factorisation order
  VectorXd u_;               // multipliers of active_, same order
  std::vector<char> is_active_;
  int iterations_ = 0;
};

void ActiveSetSolver::Directions(int k) {
  const int q = static_cast<int>(active_.size());
  d_ = J_.transpose() * Normal(k);
  z_ = J_.rightCols(n_ - q) * d_.tail(n_ - q);
  if (q > 0) {
    r_ = R_.topLeftCorner(q, q).triangularView<Eigen::Upper>().solve(d_.head(q));
  } else {
    r_.resize(0);
  }
}

void ActiveSetSolver::AddToFactorization() {
  const int q = static_cast<int>(active_.size());  // before adding
  for (int j = n_ - 1; j > q; --j) {
    double c, s, h;
    Givens(d_(j - 1), d_(j), &c, &s, &h);
    if (s == 0.0) continue;
    d_(j - 1) = h;
    d_(j) = 0.0;
    for (int row = 0; row < n_; ++row) {
      const double a = J_(row, j - 1), b = J_(row, j);
      J_(row, j - 1) = c * a + s * b;
      J_(row, j) = -s * a + c * b;
    }
  }
  R_.col(q).head(q + 1) = d_.head(q + 1);
}

void ActiveSetSolver::DropFromFactorization(int position) {
  const int q = static_cast<int>(active_.size());  // before removal
  for (int col = position; col < q - 1; ++col) R_.col(col) = R_.col(col + 1);
  R_.col(q - 1).setZero();
  for (int j = position; j < q - 1; ++j) {
    double c, s, h;
    Givens(R_(j, j), R_(j + 1, j), &c, &s, &h);
    if (s == 0.0) continue;
    for (int col = j; col < q - 1; ++col) {
      const double a = R_(j, col), b = R_(j + 1, col);
      R_(j, col) = c * a + s * b;
      R_(j + 1, col) = -s * a + c * b;
    }
    for (int row = 0; row < n_; ++row) {
      const double a = J_(row, j), b = J_(row, j + 1);
      J_(row, j) = c * a + s * b;
      J_(row, j + 1) = -s * a + c * b;
    }
  }
  active_.erase(active_.begin() + position);
  for (int k = position; k < q - 1; ++k) u_(k) = u_(k + 1);
  u_.conservativeResize(q - 1);
}

int ActiveSetSolver::MostViolated() const {
  // Relative violation: slack / max(1, |b|, |a| |x|).
  const double x_norm = x_.norm();
  auto violation = [&](int k, double slack) {
    return slack / std::max({1.0, std::abs(rhs_(k)), normal_norms_(k) * x_norm});
  };
  for (int row : settings_.warm_start) {
    const int k = p_ + row;
    if (row >= 0 && row < m_ && !is_active_[k] &&
        violation(k, Slack(k)) < -settings_.tolerance)
      return k;
  }
  if (m_ == 0) return -1;
  const VectorXd slack = rhs_.tail(m_) - normals_.rightCols(m_).transpose() * x_;
  int worst = -1;
  double worst_ratio = -settings_.tolerance;
  for (int i = 0; i < m_; ++i) {
    const int k = p_ + i;
    if (is_active_[k] || slack(i) >= 0.0) continue;
    const double ratio = violation(k, slack(i));
    if (ratio < worst_ratio) {
      worst_ratio = ratio;
      worst = k;
    }
  }
  return worst;
}

DenseQpResult ActiveSetSolver::Finish(DenseQpStatus status, int blocking) {
  DenseQpResult out;
  out.status = status;
  out.x = x_;
  out.objective = 0.5 * x_.dot(qp_.hessian * x_) + qp_.gradient.dot(x_);
  out.in_multipliers = VectorXd::Zero(m_);
  out.eq_multipliers = VectorXd::Zero(p_);
  for (int i = 0; i < static_cast<int>(active_.size()); ++i) {
    if (active_[i] < p_) {
      out.eq_multipliers(active_[i]) = u_(i);
    } else {
      out.in_multipliers(active_[i] - p_) = u_(i);
      out.active_set.push_back(active_[i] - p_);
    }
  }
  out.iterations = iterations_;
  out.blocking_row = blocking < 0 ? -1 : (blocking < p_ ? -1 - blocking : blocking - p_);
  return out;
}

bool ActiveSetSolver::Initialize() {
  is_active_.assign(p_ + m_, 0);
  u_.resize(0);
  normals_.resize(n_, p_ + m_);
  if (p_ > 0) normals_.leftCols(p_) = qp_.eq_matrix.transpose();
  if (m_ > 0) normals_.rightCols(m_) = qp_.in_matrix.transpose();
  rhs_.resize(p_ + m_);
  rhs_ << qp_.eq_rhs, qp_.in_rhs;
  normal_norms_ = normals_.colwise().norm().transpose();
  Eigen::LLT<MatrixXd> llt(qp_.hessian);
  if (llt.info() != Eigen::Success) {
    x_ = VectorXd::Zero(n_);
    return false;
  }
  // J = L^-T; unconstrained minimum x = -H^-1 g.
  J_ = llt.matrixU().solve(MatrixXd::Identity(n_, n_));
  R_ = MatrixXd::Zero(n_, n_);
  x_ = -llt.solve(qp_.gradient);
  return true;
}

int ActiveSetSolver::AddEqualities() {
  const double tol = settings_.tolerance;
  for (int k = 0; k < p_; ++k) {
    Directions(k);
    const double zn = z_.dot(Normal(k));
    if (z_.norm() <= tol * std::max(1.0, Normal(k).norm()) || std::abs(zn) <= tol) {
      // Dependent on earlier equalities: redundant if already satisfied.
      if (std::abs(Slack(k)) <= 1e3 * tol * Scale(k)) continue;
      return k;
    }
    const double t = -Slack(k) / zn;  // moves x onto the hyperplane
    x_ -= t * z_;
    if (r_.size() > 0) u_ -= t * r_;
    AddToFactorization();
    active_.push_back(k);
    is_active_[k] = 1;
    u_.conservativeResize(u_.size() + 1);
    u_(u_.size() - 1) = t;
  }
  return -1;
}

int ActiveSetSolver::BlockingActive(double* step) const {
  // Along the step x -= t z the multipliers move as u -= t r.
  *step = kInf;
  int drop = -1;
  for (int i = 0; i < static_cast<int>(active_.size()); ++i) {
    if (active_[i] < p_ || r_(i) <= settings_.tolerance) continue;
    const double ratio = u_(i) / r_(i);
    if (ratio < *step) {
      *step = ratio;
      drop = i;
    }
  }
  return drop;
}

std::optional<DenseQpStatus> ActiveSetSolver::AddInequality(int k, int max_iterations) {
  const double tol = settings_.tolerance;
  double u_new = 0.0;  // multiplier of the constraint being added
  while (true) {
    if (++iterations_ > max_iterations) return DenseQpStatus::kIterationLimit;
    Directions(k);
    const int q = static_cast<int>(active_.size());
    double t1;  // partial step length
    const int drop = BlockingActive(&t1);
    const double zn = z_.dot(Normal(k));
    double t2 = kInf;  // full step length
    if (z_.norm() > tol * std::max(1.0, Normal(k).norm()) && zn > tol * tol) {
      t2 = -Slack(k) / zn;
    }
    if (t1 == kInf && t2 == kInf) return DenseQpStatus::kInfeasible;
    if (t2 == kInf) {  // dual-only step, then drop
      if (q > 0) u_ -= t1 * r_;
      u_new += t1;
      is_active_[active_[drop]] = 0;
      DropFromFactorization(drop);
      continue;
    }
    const double t = std::min(t1, t2);
    x_ -= t * z_;
    if (q > 0) u_ -= t * r_;
    u_new += t;
    if (t2 <= t1) {
      AddToFactorization();
      active_.push_back(k);
      is_active_[k] = 1;
      u_.conservativeResize(q + 1);
      u_(q) = u_new;
      return std::nullopt;
    }
    is_active_[active_[drop]] = 0;
    DropFromFactorization(drop);
  }
}

DenseQpResult ActiveSetSolver::Run() {
  if (!Initialize()) return Finish(DenseQpStatus::kNumericalError, -1);
  const int max_iterations =
      settings_.max_iterations > 0 ? settings_.max_iterations : 5 * (n_ + m_ + p_) + 20;
  // Equalities first: each becomes active with a multiplier of either sign.
  if (const int inconsistent = AddEqualities(); inconsistent >= 0) {
    return Finish(DenseQpStatus::kInfeasible, inconsistent);
  }
  while (true) {
    const int k = MostViolated();
    if (k < 0) return Finish(DenseQpStatus::kOptimal, -1);
    if (const std::optional<DenseQpStatus> stop = AddInequality(k, max_iterations)) {
      return Finish(*stop, k);
    }
  }
}

}  // namespace

DenseQpResult SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings) {
  ActiveSetSolver solver(qp, settings);
  return solver.Run();
}

}  // namespace tactforce::planner
