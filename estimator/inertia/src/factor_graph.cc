// FACTOR_GRAPH: Sundaralingam & Hermans III-B, reproduced as published.
//
// Variables: the inertial block w = [m, c, Lx, Ly, Lz, R in SO(3)] (inertia
// about the object ORIGIN H = R diag(Ly+Lz, Lx+Lz, Lx+Ly) R^T, as eq. 9 uses
// it) and every object pose X_t (right perturbation of R_t, world p_t).
// Factors:
//   D_t  dynamics (eq. 8-19) from X_{t-2}, X_{t-1}, X_t and the forces and
//        contacts of sample t-2; SE(3) logs (eq. 12-13), the first-order frame
//        change of eq. 14-15 and the differences of eq. 16-17 exactly as
//        written (including the mixed w_{t,t-1} / w_{t-1,t-2} products and the
//        forces of the FIRST of the three samples, a one-sample lag).
//   M    measurement factors on poses and forces. The force variables enter
//        D linearly and appear in no other factor, so they are eliminated
//        exactly: D_t is whitened by (Sigma_D + G Sigma_f G^T)^-1/2 (the
//        Schur complement of the force variables; same optimum).
//   C    m > 0, c in the hull, L >= 0 (eq. 35-37): costs active only when
//        violated, as the paper did in GTSAM.
//   B    optional prior Tr(P0^-1 P) (eq. 20-21), as the residual
//        sqrt(weight) (Tr(P0^-1 P) - 4).
// Batch Levenberg-Marquardt on the sparse normal equations, solved by a
// block-banded Cholesky of the pose blocks and a Schur complement on the
// inertial block (exact, O(N)).
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <unsupported/Eigen/AutoDiff>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "internal.h"
#include "tactforce/inertia/pseudo_inertia.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::inertia::internal {
namespace {

constexpr int kLocal = 28;  // 3 poses x 6 + 10 inertial
using Deriv = Eigen::Matrix<double, kLocal, 1>;
using Jet = Eigen::AutoDiffScalar<Deriv>;

template <typename T>
using V3 = Eigen::Matrix<T, 3, 1>;
template <typename T>
using M3 = Eigen::Matrix<T, 3, 3>;

template <typename T>
M3<T> Hat(const V3<T>& v) {
  M3<T> m;
  m << T(0), -v(2), v(1), v(2), T(0), -v(0), -v(1), v(0), T(0);
  return m;
}

template <typename T>
V3<T> LogRot(const M3<T>& R) {
  using std::atan2;
  using std::sqrt;
  V3<T> v(T(0.5) * (R(2, 1) - R(1, 2)), T(0.5) * (R(0, 2) - R(2, 0)), T(0.5) * (R(1, 0) - R(0, 1)));
  const T c = T(0.5) * (R(0, 0) + R(1, 1) + R(2, 2) - T(1));
  const T s2 = v.squaredNorm();
  if (s2 < T(1e-14)) return v * (T(1) + s2 / T(6));
  const T s = sqrt(s2);
  const T theta = atan2(s, c);
  return v * (theta / s);
}

// SE(3) log of (R, t): rotation vector phi and translation part rho.
template <typename T>
void LogSE3(const M3<T>& R, const V3<T>& t, V3<T>* phi, V3<T>* rho) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  *phi = LogRot(R);
  const T th2 = phi->squaredNorm();
  T beta;
  if (th2 < T(1e-8)) {
    beta = T(1.0 / 12.0) + th2 / T(720.0);
  } else {
    const T th = sqrt(th2);
    beta = (T(1) - th * sin(th) / (T(2) * (T(1) - cos(th)))) / th2;
  }
  const M3<T> P = Hat(*phi);
  *rho = t - T(0.5) * (P * t) + beta * (P * (P * t));
}

template <typename T>
Eigen::Matrix<T, 6, 1> Dynamics(const M3<T>& R0, const V3<T>& p0, const M3<T>& R1, const V3<T>& p1,
                                const M3<T>& R2, const V3<T>& p2, double dt1, double dt2,
                                const T& m, const V3<T>& c, const M3<T>& H, const Vec3& g,
                                const Vector6d& wrench) {
  V3<T> phi_a, rho_a, phi_b, rho_b;
  LogSE3<T>(R0.transpose() * R1, R0.transpose() * (p1 - p0), &phi_a, &rho_a);  // eq. 10, 12
  LogSE3<T>(R1.transpose() * R2, R1.transpose() * (p2 - p1), &phi_b, &rho_b);  // eq. 11, 13
  const V3<T> w1 = phi_a / T(dt1), v1 = rho_a / T(dt1);
  const V3<T> w2 = phi_b / T(dt2), v2 = rho_b / T(dt2);
  const V3<T> w2p = w2 + w1.cross(w2) * T(dt2);  // eq. 14
  const V3<T> v2p = v2 + w1.cross(v2) * T(dt2);  // eq. 15
  const V3<T> dw = (w2p - w1) / T(dt2);          // eq. 16
  const V3<T> a = (v2p - v1) / T(dt2);           // eq. 17
  const V3<T> g0 = R0.transpose() * g.cast<T>();
  const V3<T> amg = a - g0;
  const V3<T> A = m * amg - m * c.cross(dw) + m * w2p.cross(w1.cross(c));  // eq. 18
  const V3<T> B = m * c.cross(amg) + H * dw + w2p.cross(H * w1);           // eq. 19
  Eigen::Matrix<T, 6, 1> r;
  r.template head<3>() = A - wrench.head<3>().cast<T>();
  r.template tail<3>() = B - wrench.tail<3>().cast<T>();
  return r;
}

// Inertia about the origin from the paper's parameterisation (eq. 26-30).
template <typename T>
M3<T> InertiaFromL(const V3<T>& L, const M3<T>& Rl) {
  M3<T> Hd = M3<T>::Zero();
  Hd(0, 0) = L(1) + L(2);
  Hd(1, 1) = L(0) + L(2);
  Hd(2, 2) = L(0) + L(1);
  return Rl * Hd * Rl.transpose();
}

// Inertia about the origin from Baseline-FG's raw entries [xx, yy, zz, xy, xz, yz].
template <typename T>
M3<T> InertiaFromEntries(const Eigen::Matrix<T, 6, 1>& h) {
  M3<T> H;
  H << h(0), h(3), h(4), h(3), h(1), h(5), h(4), h(5), h(2);
  return H;
}

// Pseudo-inertia of the paper's variables: second moment about the origin
// Sigma = R diag(L) R^T, first moment m c.
template <typename T>
PseudoInertiaTpl<T> PseudoOfVariables(const T& m, const V3<T>& c, const V3<T>& L, const M3<T>& Rl) {
  PseudoInertiaTpl<T> j;
  j.mass = m;
  j.h = m * c;
  j.sigma = Rl * L.asDiagonal() * Rl.transpose();
  return j;
}

// The inertial variables: [m, c, L, R] (the paper's w), or with `raw`
// Baseline-FG's [m, c, h] (h = the six entries of H about the origin).
struct Inertial {
  bool raw = false;
  double m = 1;
  Vec3 c = Vec3::Zero();
  Vec3 L = Vec3::Ones();
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Vector6d h = Vector6d::Zero();

  Eigen::Matrix3d InertiaOrigin() const {
    return raw ? InertiaFromEntries<double>(h) : InertiaFromL<double>(L, R);
  }
  Vector10d Standard() const {
    const Eigen::Matrix3d Io = InertiaOrigin();
    Vector10d pi;
    pi << m, m * c, Io(0, 0), Io(1, 1), Io(2, 2), Io(0, 1), Io(0, 2), Io(1, 2);
    return pi;
  }
  // Sets the inertia about the origin to that of second moment S.
  void SetSecondMoment(const Eigen::Matrix3d& S) {
    const Eigen::Matrix3d Io = S.trace() * Eigen::Matrix3d::Identity() - S;
    h << Io(0, 0), Io(1, 1), Io(2, 2), Io(0, 1), Io(0, 2), Io(1, 2);
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(S);
    L = es.eigenvalues();
    R = es.eigenvectors();
    if (R.determinant() < 0) R.col(2) = -R.col(2);
  }
  void Retract(const Eigen::Ref<const Eigen::VectorXd>& d) {
    m += d(0);
    c += d.segment<3>(1);
    if (raw) {
      h += d.segment<6>(4);
      return;
    }
    L += d.segment<3>(4);
    R = R * ExpSO3(d.segment<3>(7));
  }
};

struct Pose {
  Eigen::Matrix3d R;
  Vec3 p;
};

Jet Var(double v, int i) {
  Jet j(v);
  j.derivatives() = Deriv::Unit(i);
  return j;
}
Jet Const(double v) {
  Jet j(v);
  j.derivatives().setZero();
  return j;
}

// The inertial block as AutoDiff variables 18..27 (local perturbations of
// R for the paper's w): m, c and the inertia about the origin H.
void InertialJets(const Inertial& in, Jet* m, V3<Jet>* c, M3<Jet>* H) {
  *m = Var(in.m, 18);
  *c = V3<Jet>(Var(in.c(0), 19), Var(in.c(1), 20), Var(in.c(2), 21));
  if (in.raw) {
    Eigen::Matrix<Jet, 6, 1> h;
    for (int i = 0; i < 6; ++i) h(i) = Var(in.h(i), 22 + i);
    *H = InertiaFromEntries<Jet>(h);
    return;
  }
  const V3<Jet> L(Var(in.L(0), 22), Var(in.L(1), 23), Var(in.L(2), 24));
  const V3<Jet> dr(Var(0, 25), Var(0, 26), Var(0, 27));
  *H = InertiaFromL<Jet>(L, in.R.cast<Jet>() * (M3<Jet>::Identity() + Hat<Jet>(dr)));
}

Eigen::Matrix3d InvRightJacobian(const Vec3& phi) {
  const double th = phi.norm();
  const Eigen::Matrix3d P = Skew(phi);
  if (th < 1e-6) return Eigen::Matrix3d::Identity() + 0.5 * P + P * P / 12.0;
  const double k = 1.0 / (th * th) - (1 + std::cos(th)) / (2 * th * std::sin(th));
  return Eigen::Matrix3d::Identity() + 0.5 * P + k * P * P;
}

// Gauss-Newton normal equations with the structure of the problem: pose
// blocks couple only within three consecutive samples (block bandwidth 2),
// the 10 inertial variables couple with everything.
//   [ B  E ] [dp]     [gp]
//   [ E' C ] [di] = - [gi]
struct NormalEquations {
  std::vector<std::array<Matrix6d, 3>> B;  // B[k][d]: block (k, k+d)
  std::vector<Eigen::Matrix<double, 6, 10>> E;
  std::vector<Vector6d> gp;
  Matrix10d C;
  Vector10d gi;

  // Zeroes every block in a polled loop (the blocks of a long data set are
  // gigabytes); false when `poll` fired.
  bool Reset(int n, InterruptPoll* poll) {
    B.clear(), E.clear(), gp.clear();  // the capacity stays
    B.reserve(n), E.reserve(n), gp.reserve(n);
    C.setZero();
    gi.setZero();
    for (int k = 0; k < n; ++k) {
      if (poll->Tick()) return false;
      B.push_back({Matrix6d::Zero(), Matrix6d::Zero(), Matrix6d::Zero()});
      E.push_back(Eigen::Matrix<double, 6, 10>::Zero());
      gp.push_back(Vector6d::Zero());
    }
    return true;
  }
};

// Block-banded Cholesky B = L L^T (L(k,k-1), L(k,k-2) below the diagonal).
class BandedCholesky {
 public:
  // False when B + lambda diag(B) is not positive definite or `poll` fired.
  bool Factor(const NormalEquations& ne, double lambda, InterruptPoll* poll) {
    const int n = static_cast<int>(ne.B.size());
    d_.clear(), l1_.clear(), l2_.clear();  // filled in the polled loop
    d_.reserve(n), l1_.reserve(n), l2_.reserve(n);
    for (int k = 0; k < n; ++k) {
      if (poll->Tick(2)) return false;
      d_.emplace_back();
      l1_.push_back(Matrix6d::Zero());
      l2_.push_back(Matrix6d::Zero());
      if (k >= 2) l2_[k] = d_[k - 2].matrixL().solve(ne.B[k - 2][2]).transpose();  // B(k,k-2) L^-T
      if (k >= 1) {
        Matrix6d rhs = ne.B[k - 1][1].transpose();
        if (k >= 2) rhs -= l2_[k] * l1_[k - 1].transpose();
        l1_[k] = d_[k - 1].matrixL().solve(rhs.transpose()).transpose();
      }
      Matrix6d D = ne.B[k][0];
      D.diagonal() += lambda * D.diagonal().cwiseMax(1e-12);
      if (k >= 1) D -= l1_[k] * l1_[k].transpose();
      if (k >= 2) D -= l2_[k] * l2_[k].transpose();
      d_[k].compute(D);
      if (d_[k].info() != Eigen::Success) return false;
    }
    return true;
  }
  // Solves B X = Y in place (Y: n blocks of 6 rows); incomplete when `poll` fires.
  template <int Cols>
  void Solve(std::vector<Eigen::Matrix<double, 6, Cols>>& y, InterruptPoll* poll) const {
    const int n = static_cast<int>(y.size());
    for (int k = 0; k < n; ++k) {  // forward: L z = y
      if (poll->Tick(Cols > 1 ? 2 : 1)) return;
      if (k >= 1) y[k] -= l1_[k] * y[k - 1];
      if (k >= 2) y[k] -= l2_[k] * y[k - 2];
      y[k] = d_[k].matrixL().solve(y[k]);
    }
    for (int k = n - 1; k >= 0; --k) {  // backward: L^T x = z
      if (poll->Tick(Cols > 1 ? 2 : 1)) return;
      if (k + 1 < n) y[k] -= l1_[k + 1].transpose() * y[k + 1];
      if (k + 2 < n) y[k] -= l2_[k + 2].transpose() * y[k + 2];
      y[k] = d_[k].matrixU().solve(y[k]);
    }
  }

 private:
  std::vector<Eigen::LLT<Matrix6d>> d_;
  std::vector<Matrix6d> l1_, l2_;
};

// *to = from in a polled loop; false when `poll` fired.
template <typename Block>
bool PolledCopy(const std::vector<Block>& from, std::vector<Block>* to, InterruptPoll* poll) {
  to->clear();
  to->reserve(from.size());
  for (const Block& b : from) {
    if (poll->Tick()) return false;
    to->push_back(b);
  }
  return true;
}

// Damped step: (H + lambda diag(H)) d = -g; false if not positive definite
// or `poll` fired. With `cov`, also returns the inertial block of H^-1
// (lambda should be 0).
bool SolveStep(const NormalEquations& ne, double lambda, Eigen::VectorXd* step, Matrix10d* cov,
               InterruptPoll* poll) {
  const int n = static_cast<int>(ne.B.size());
  BandedCholesky chol;
  if (!chol.Factor(ne, lambda, poll)) return false;
  std::vector<Eigen::Matrix<double, 6, 10>> BE;
  std::vector<Eigen::Matrix<double, 6, 1>> Bg;
  if (!PolledCopy(ne.E, &BE, poll) || !PolledCopy(ne.gp, &Bg, poll)) return false;
  chol.Solve<10>(BE, poll);
  chol.Solve<1>(Bg, poll);
  Matrix10d S = ne.C;
  S.diagonal() += lambda * ne.C.diagonal().cwiseMax(1e-12);
  Vector10d rhs = ne.gi;
  for (int k = 0; k < n; ++k) {
    if (poll->Tick()) return false;
    S -= ne.E[k].transpose() * BE[k];
    rhs -= ne.E[k].transpose() * Bg[k];
  }
  S = 0.5 * (S + S.transpose());
  Eigen::LDLT<Matrix10d> ldlt(S);
  if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
  const Vector10d di = -ldlt.solve(rhs);
  if (!di.allFinite()) return false;
  if (cov) *cov = ldlt.solve(Matrix10d::Identity());
  if (step) {
    step->resize(10 + 6 * n);
    step->head<10>() = di;
    for (int k = 0; k < n; ++k) step->segment<6>(10 + 6 * k) = -(Bg[k] + BE[k] * di);
  }
  return true;
}

// The variants with the constraint factor C; those with the prior B (fg-c
// keeps the earlier FACTOR_GRAPH's behaviour: B when a prior is given).
bool UsesConstraints(FactorGraphVariant v) {
  return v == FactorGraphVariant::kConstraint || v == FactorGraphVariant::kConstraintPrior;
}
bool UsesPrior(const InertiaOptions& o) {
  return UsesConstraints(o.factor_graph.variant) && o.prior.has_value();
}

class Problem {
 public:
  // Stops early (check poll->stopped()) when `poll` fires; so do the loops
  // of Evaluate (then NaN), Retract and DynamicsRms.
  Problem(const InertiaSamples& s, const InertiaOptions& o, const ConvexHull* hull,
          InterruptPoll* poll)
      : s_(s), o_(o), hull_(hull), n_(static_cast<int>(s.samples.size())), poll_(poll) {
    meas_.resize(n_);
    for (int k = 0; k < n_; ++k) {
      if (poll_->Tick()) return;
      meas_[k].R = s.samples[k].orientation.toRotationMatrix();
      meas_[k].p = s.samples[k].position;
    }
    sig_p_ = std::max(o.noise.position_sigma, o.factor_graph.min_position_sigma);
    sig_r_ = std::max(o.noise.orientation_sigma, o.factor_graph.min_orientation_sigma);
    // Whitening of each dynamics factor: (Sigma_D + G Sigma_f G^T)^-1/2.
    InertiaNoise floored = o.noise;
    floored.force_sigma = std::max(o.noise.force_sigma, o.factor_graph.min_force_sigma);
    floored.torque_sigma = std::max(o.noise.torque_sigma, o.factor_graph.min_torque_sigma);
    whiten_.reserve(std::max(0, n_ - 2));
    wrench_.reserve(std::max(0, n_ - 2));
    for (int k = 0; k + 2 < n_; ++k) {
      if (poll_->Tick()) return;
      const InertiaSample& x = s.samples[k];
      Matrix6d C;
      WrenchCovariance(x, s.source, floored, &C);
      const FactorGraphOptions& fg = o.factor_graph;
      C.diagonal().head<3>().array() += fg.dynamics_force_sigma * fg.dynamics_force_sigma;
      C.diagonal().tail<3>().array() += fg.dynamics_torque_sigma * fg.dynamics_torque_sigma;
      // W with W^T W = C^-1: W = L^-1 for C = L L^T.
      const Eigen::LLT<Matrix6d> llt(C);
      Matrix6d W = llt.matrixL().solve(Matrix6d::Identity());
      whiten_.push_back(W);
      wrench_.push_back(SampleWrench(x, s.source));
    }
  }

  // Initial values: poses as measured; m and m c from the force rows of the
  // three-point kinematics; second moment of a small ball around c.
  void Initialise(double m0, const Vec3& c0, double radius) {
    poses_ = meas_;
    in_.raw = o_.factor_graph.variant == FactorGraphVariant::kBaselineFg;
    in_.m = m0;
    in_.c = c0;
    in_.SetSecondMoment(m0 * (c0 * c0.transpose() + radius * radius * Eigen::Matrix3d::Identity()));
  }

  // Cost; with `ne`, also the Gauss-Newton normal equations. The factors
  // are added in a fixed order (dynamics, poses, constraints, prior).
  double Evaluate(NormalEquations* ne) const {
    double cost = 0;
    if (ne && !ne->Reset(n_, poll_)) return std::numeric_limits<double>::quiet_NaN();
    for (int k = 0; k + 2 < n_; ++k) {
      if (poll_->Tick(ne ? 16 : 1)) return std::numeric_limits<double>::quiet_NaN();
      AddDynamicsFactor(k, ne, &cost);
    }
    AddPoseFactors(ne, &cost);
    AddConstraintFactors(ne, &cost);
    AddTracePrior(ne, &cost);
    return cost;
  }

  void Retract(const Eigen::VectorXd& d) {
    in_.Retract(d.head<10>());
    for (int k = 0; k < n_; ++k) {
      if (poll_->Tick()) return;
      poses_[k].R = poses_[k].R * ExpSO3(d.segment<3>(10 + 6 * k));
      poses_[k].p += d.segment<3>(10 + 6 * k + 3);
    }
  }

  // Unwhitened dynamics residual RMS (force, torque).
  void DynamicsRms(double* f, double* t) const {
    double sf = 0, st = 0;
    int cnt = 0;
    for (int k = 0; k + 2 < n_; ++k) {
      if (poll_->Tick()) break;
      const double dt1 = s_.samples[k + 1].t - s_.samples[k].t,
                   dt2 = s_.samples[k + 2].t - s_.samples[k + 1].t;
      const Pose &a = poses_[k], &b = poses_[k + 1], &c = poses_[k + 2];
      const Vector6d e = Dynamics<double>(a.R, a.p, b.R, b.p, c.R, c.p, dt1, dt2, in_.m, in_.c,
                                          in_.InertiaOrigin(), o_.gravity, wrench_[k]);
      sf += e.head<3>().squaredNorm();
      st += e.tail<3>().squaredNorm();
      ++cnt;
    }
    *f = std::sqrt(sf / std::max(1, 3 * cnt));
    *t = std::sqrt(st / std::max(1, 3 * cnt));
  }

  Inertial& inertial() { return in_; }
  const std::vector<Matrix6d>& whiten() const { return whiten_; }
  void SetScales(double m, double l) { m_scale_ = m, l_scale_ = l; }
  std::vector<Pose> poses_;

 private:
  // Dynamics factor D_k from poses k, k+1, k+2 (with `ne`: its Jacobian by
  // forward-mode AutoDiff into the normal equations).
  void AddDynamicsFactor(int k, NormalEquations* ne, double* cost) const {
    const Vec3& g = o_.gravity;
    const double dt1 = s_.samples[k + 1].t - s_.samples[k].t,
                 dt2 = s_.samples[k + 2].t - s_.samples[k + 1].t;
    const Pose &a = poses_[k], &b = poses_[k + 1], &cpose = poses_[k + 2];
    Vector6d e;
    if (!ne) {
      e = Dynamics<double>(a.R, a.p, b.R, b.p, cpose.R, cpose.p, dt1, dt2, in_.m, in_.c,
                           in_.InertiaOrigin(), g, wrench_[k]);
      *cost += 0.5 * (whiten_[k] * e).squaredNorm();
      return;
    }
    M3<Jet> R[3];
    V3<Jet> P[3];
    const Pose* ps[3] = {&a, &b, &cpose};
    for (int q = 0; q < 3; ++q) {
      V3<Jet> d(Var(0, 6 * q), Var(0, 6 * q + 1), Var(0, 6 * q + 2));
      R[q] = ps[q]->R.cast<Jet>() * (M3<Jet>::Identity() + Hat<Jet>(d));
      P[q] =
          ps[q]->p.cast<Jet>() + V3<Jet>(Var(0, 6 * q + 3), Var(0, 6 * q + 4), Var(0, 6 * q + 5));
    }
    Jet m;
    V3<Jet> c;
    M3<Jet> H;
    InertialJets(in_, &m, &c, &H);
    const Eigen::Matrix<Jet, 6, 1> ej =
        Dynamics<Jet>(R[0], P[0], R[1], P[1], R[2], P[2], dt1, dt2, m, c, H, g, wrench_[k]);
    Eigen::Matrix<double, 6, kLocal> Jl;
    for (int i = 0; i < 6; ++i) e(i) = ej(i).value(), Jl.row(i) = ej(i).derivatives().transpose();
    const Eigen::Matrix<double, 6, kLocal> Jw = whiten_[k] * Jl;
    const Vector6d ew = whiten_[k] * e;
    *cost += 0.5 * ew.squaredNorm();
    const Eigen::Matrix<double, kLocal, kLocal> JtJ = Jw.transpose() * Jw;
    const Eigen::Matrix<double, kLocal, 1> Jte = Jw.transpose() * ew;
    for (int q = 0; q < 3; ++q) {
      for (int q2 = q; q2 < 3; ++q2) ne->B[k + q][q2 - q] += JtJ.block<6, 6>(6 * q, 6 * q2);
      ne->E[k + q] += JtJ.block<6, 10>(6 * q, 18);
      ne->gp[k + q] += Jte.segment<6>(6 * q);
    }
    ne->C += JtJ.block<10, 10>(18, 18);
    ne->gi += Jte.segment<10>(18);
  }

  // Pose measurement factors.
  void AddPoseFactors(NormalEquations* ne, double* cost) const {
    for (int k = 0; k < n_; ++k) {
      if (poll_->Tick()) return;
      const Vec3 phi = LogSO3(meas_[k].R.transpose() * poses_[k].R);
      const Vec3 dp = poses_[k].p - meas_[k].p;
      *cost += 0.5 * (phi.squaredNorm() / (sig_r_ * sig_r_) + dp.squaredNorm() / (sig_p_ * sig_p_));
      if (ne) {
        const Eigen::Matrix3d Jr = InvRightJacobian(phi) / sig_r_;
        ne->B[k][0].topLeftCorner<3, 3>() += Jr.transpose() * Jr;
        ne->B[k][0].bottomRightCorner<3, 3>().diagonal().array() += 1.0 / (sig_p_ * sig_p_);
        ne->gp[k].head<3>() += Jr.transpose() * (phi / sig_r_);
        ne->gp[k].tail<3>() += dp / (sig_p_ * sig_p_);
      }
    }
  }

  // A residual r on the inertial block with Jacobian j.
  static void AddInertialResidual(double r, const Vector10d& j, NormalEquations* ne, double* cost) {
    *cost += 0.5 * r * r;
    if (ne) {
      ne->C += j * j.transpose();
      ne->gi += j * r;
    }
  }

  // Constraint factors on the inertial block, active only when violated
  // (fg-c and fg-c-g only).
  void AddConstraintFactors(NormalEquations* ne, double* cost) const {
    if (!UsesConstraints(o_.factor_graph.variant)) return;
    const double sigma = o_.factor_graph.constraint_sigma;
    const double sm = sigma * m_scale_, sl = sigma * m_scale_ * l_scale_ * l_scale_,
                 sc = sigma * l_scale_;
    const double m_min = 1e-6 * m_scale_;
    if (in_.m < m_min)
      AddInertialResidual((m_min - in_.m) / sm, -Vector10d::Unit(0) / sm, ne, cost);
    for (int i = 0; i < 3; ++i)
      if (in_.L(i) < 0) AddInertialResidual(-in_.L(i) / sl, -Vector10d::Unit(4 + i) / sl, ne, cost);
    if (!hull_) return;
    for (size_t j = 0; j < hull_->normals.size(); ++j) {
      const double v = hull_->normals[j].dot(in_.c) - hull_->offsets[j];
      if (v > 0) {
        Vector10d jac = Vector10d::Zero();
        jac.segment<3>(1) = hull_->normals[j] / sc;
        AddInertialResidual(v / sc, jac, ne, cost);
      }
    }
  }

  // Trace prior (eq. 20).
  void AddTracePrior(NormalEquations* ne, double* cost) const {
    if (!UsesPrior(o_) || !(o_.prior->weight > 0)) return;
    const double sw = std::sqrt(o_.prior->weight);
    const Eigen::Matrix4d P0inv =
        PseudoInertiaD::FromParameters(o_.prior->params).Matrix().inverse();
    const Jet m = Var(in_.m, 18);
    const V3<Jet> c(Var(in_.c(0), 19), Var(in_.c(1), 20), Var(in_.c(2), 21));
    const V3<Jet> L(Var(in_.L(0), 22), Var(in_.L(1), 23), Var(in_.L(2), 24));
    const V3<Jet> dr(Var(0, 25), Var(0, 26), Var(0, 27));
    const M3<Jet> Rl = in_.R.cast<Jet>() * (M3<Jet>::Identity() + Hat<Jet>(dr));
    const Eigen::Matrix<Jet, 4, 4> P = PseudoOfVariables<Jet>(m, c, L, Rl).Matrix();
    Jet tr = Const(0);
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j) tr += P0inv(i, j) * P(j, i);
    AddInertialResidual(sw * (tr.value() - 4.0), sw * tr.derivatives().segment<10>(18), ne, cost);
  }

  const InertiaSamples& s_;
  const InertiaOptions& o_;
  const ConvexHull* hull_;
  const int n_;
  InterruptPoll* poll_;
  std::vector<Pose> meas_;
  std::vector<Matrix6d> whiten_;
  std::vector<Vector6d> wrench_;
  double sig_p_ = 1e-6, sig_r_ = 1e-6;
  double m_scale_ = 1, l_scale_ = 0.1;
  Inertial in_;
};

// The factor graph's finite differences need rotations below 90 degrees
// between consecutive samples.
absl::Status CheckRotationSteps(const InertiaSamples& s, InterruptPoll* poll) {
  const int n = static_cast<int>(s.samples.size());
  for (int k = 0; k + 1 < n; ++k) {
    if (poll->Tick()) return Interrupted();
    const Eigen::Matrix3d Rr = s.samples[k].orientation.toRotationMatrix().transpose() *
                               s.samples[k + 1].orientation.toRotationMatrix();
    if (LogSO3(Rr).norm() > M_PI / 2) {
      return absl::InvalidArgumentError(
          absl::StrCat(s.line_numbers.size() > static_cast<size_t>(k + 1)
                           ? absl::StrCat(s.source_name, ":", s.line_numbers[k + 1])
                           : absl::StrCat("samples[", k + 1, "]"),
                       ": the orientation changes by more than 90 degrees since the previous "
                       "sample; the factor graph's "
                       "finite differences need a higher sample rate"));
    }
  }
  return absl::OkStatus();
}

// Neutral initial values: m and m c from the force rows with three-point
// kinematics (the prior's when given), a ball of radius `len` around c.
struct InitialInertial {
  double m0 = 1;
  Vec3 c0 = Vec3::Zero();
  double len = 0.1;
};

InitialInertial InitialFromForces(const InertiaSamples& s, const InertiaOptions& o,
                                  const ConvexHull* hull, const std::vector<KinPoint>& kin,
                                  InterruptPoll* poll) {
  StackedLeastSquares ls(4);
  double force_sq = 0;  // |all force rows|^2
  for (size_t i = 0; i < kin.size(); ++i) {
    if (poll->Tick()) break;
    const Matrix6x10 Y = Regressor(kin[i].w, kin[i].dw, kin[i].a_minus_g);
    const Vec3 f = SampleWrench(s.samples[kin[i].index], s.source).head<3>();
    ls.Add(Y.topLeftCorner<3, 4>(), f);
    force_sq += f.squaredNorm();
  }
  InitialInertial init;
  const Eigen::MatrixXd& t = ls.Triangle();
  const Eigen::Matrix4d R = t.topLeftCorner<4, 4>();
  Eigen::Vector4d mh = R.colPivHouseholderQr().solve(Eigen::Vector4d(t.col(4).head<4>()));
  init.m0 = mh(0);
  if (!(init.m0 > 0) || !std::isfinite(init.m0)) {
    init.m0 = std::max(std::sqrt(force_sq) / std::sqrt(static_cast<double>(kin.size())) /
                           std::max(o.gravity.norm(), 1e-9),
                       1e-3);
    mh.tail<3>().setZero();
  }
  init.c0 = mh.tail<3>() / init.m0;
  if (!init.c0.allFinite()) init.c0.setZero();
  init.len = hull ? 0.25 * hull->size : std::max(0.05, 0.5 * init.c0.norm());
  if (UsesPrior(o)) {
    init.m0 = o.prior->params.mass;
    init.c0 = o.prior->params.com;
  }
  return init;
}

// What the variant optimises, for the fit's notes.
std::string VariantNote(const InertiaOptions& o) {
  const char* what = "";
  switch (o.factor_graph.variant) {
    case FactorGraphVariant::kBaselineFg:
      what =
          "inertial variables [m, c, H_xx..H_yz] (H about the origin) as independent reals, no "
          "constraint, no prior";
      break;
    case FactorGraphVariant::kNoConstraint:
      what =
          "inertial variables [m, c, L, R in SO(3)], no constraint factor (m > 0, c in hull, L >= "
          "0 off), no prior";
      break;
    case FactorGraphVariant::kConstraint:
      what = o.prior ? "[m, c, L, R], constraint factors m > 0, c in hull, L >= 0, trace prior "
                       "(the prior given)"
                     : "[m, c, L, R], constraint factors m > 0, c in hull, L >= 0, no prior";
      break;
    case FactorGraphVariant::kConstraintPrior:
      what = "[m, c, L, R], constraint factors m > 0, c in hull, L >= 0, trace prior";
      break;
  }
  std::string note =
      absl::StrCat("factor-graph variant ", ToString(o.factor_graph.variant), ": ", what);
  if (o.prior && !UsesPrior(o)) absl::StrAppend(&note, " (prior ignored)");
  return note;
}

// Batch Levenberg-Marquardt from the problem's current values; `ne` and
// `cost` hold the normal equations and cost at the answer. Returns the
// number of iterations.
absl::StatusOr<int> LevenbergMarquardt(Problem& prob, const InertiaOptions& o, NormalEquations* ne,
                                       double* cost, InterruptPoll* poll) {
  *cost = prob.Evaluate(ne);
  if (poll->stopped()) return Interrupted();
  double lambda = 1e-4;
  int it = 0;
  for (; it < o.max_iterations; ++it) {
    if (poll->Check()) return Interrupted();
    bool accepted = false;
    double new_cost = *cost;
    for (int tries = 0; tries < 12 && !accepted; ++tries) {
      Eigen::VectorXd step;
      if (!SolveStep(*ne, lambda, &step, nullptr, poll)) {
        if (poll->stopped()) return Interrupted();
        lambda *= 10;
        continue;
      }
      const Inertial saved_in = prob.inertial();
      const std::vector<Pose> saved_poses = prob.poses_;
      prob.Retract(step);
      new_cost = prob.Evaluate(nullptr);
      if (poll->stopped()) return Interrupted();
      if (std::isfinite(new_cost) && new_cost < *cost) {
        accepted = true;
        lambda = std::max(lambda / 3, 1e-12);
      } else {
        prob.inertial() = saved_in;
        prob.poses_ = saved_poses;
        lambda *= 4;
      }
    }
    if (o.progress) o.progress(0.9 * (it + 1) / o.max_iterations);
    if (!accepted) break;
    const double dec = *cost - new_cost;
    *cost = prob.Evaluate(ne);
    if (poll->stopped()) return Interrupted();
    if (dec <= 1e-10 * *cost) {
      ++it;
      break;
    }
  }
  return it;
}

// Marginal covariance of the inertial block (Gauss-Newton), mapped to pi;
// zero when the normal equations are singular or the map is not finite.
Matrix10d InertialCovariance(Problem& prob, const NormalEquations& ne, InterruptPoll* poll) {
  Matrix10d cov_t;
  if (!SolveStep(ne, 0.0, nullptr, &cov_t, poll)) return Matrix10d::Zero();
  Matrix10d Jp;
  for (int i = 0; i < 10; ++i) {
    Inertial a = prob.inertial(), b = prob.inertial();
    Vector10d d = Vector10d::Zero();
    d(i) = 1e-7;
    a.Retract(d);
    b.Retract(-d);
    Jp.col(i) = (a.Standard() - b.Standard()) / 2e-7;
  }
  const Matrix10d c = Jp * (0.5 * (cov_t + cov_t.transpose())) * Jp.transpose();
  return c.allFinite() ? c : Matrix10d::Zero();
}

}  // namespace

absl::StatusOr<MethodOutput> FitFactorGraph(const InertiaSamples& s, const InertiaOptions& o,
                                            const ConvexHull* hull) {
  InterruptPoll poll(o.interrupt);
  MethodOutput out;
  const int n = static_cast<int>(s.samples.size());
  out.notes.push_back(VariantNote(o));
  out.notes.push_back("kinematics: three consecutive poses per dynamics factor (eq. 10-17)");
  if (s.HasKinematics())
    out.notes.push_back("measured kinematics ignored by factor-graph (poses only, as the paper)");
  TF_RETURN_IF_ERROR(CheckRotationSteps(s, &poll));

  const std::vector<KinPoint> kin = FiniteDifferenceKinematics(s, o.gravity, &poll);
  const InitialInertial init = InitialFromForces(s, o, hull, kin, &poll);
  Problem prob(s, o, hull, &poll);
  if (poll.stopped()) return Interrupted();
  prob.SetScales(init.m0, std::max(init.len, init.c0.norm()));
  prob.Initialise(init.m0, init.c0, init.len);
  if (UsesPrior(o)) {
    // Start from the prior's inertia.
    prob.inertial().SetSecondMoment(PseudoInertiaD::FromParameters(o.prior->params).sigma);
  }

  NormalEquations ne;
  double cost = 0;
  TF_ASSIGN_OR_RETURN(int it, LevenbergMarquardt(prob, o, &ne, &cost, &poll));
  out.iterations = it;
  out.pi = prob.inertial().Standard();
  out.samples_used = std::max(0, n - 2);
  prob.DynamicsRms(&out.rms_force, &out.rms_torque);
  out.notes.push_back(
      absl::StrFormat("Levenberg-Marquardt: %d iterations, final cost %.6g", it, cost));
  out.cov = InertialCovariance(prob, ne, &poll);
  // Excitation: three-point regressors whitened like the dynamics factors.
  double ms = 1, ls = 0.1;
  RoughScale(out.pi, hull, &ms, &ls);
  out.scale = ParameterScale(ms, ls);
  for (size_t i = 0; i < kin.size() && i < prob.whiten().size(); ++i) {
    if (poll.Tick()) return Interrupted();
    const Matrix6x10 Y = prob.whiten()[i] * Regressor(kin[i].w, kin[i].dw, kin[i].a_minus_g);
    out.info += Y.transpose() * Y;
  }
  if (poll.stopped()) return Interrupted();
  return out;
}

}  // namespace tactforce::inertia::internal
