// Tightening for uncertain inertial parameters and friction
// (parameter_uncertainty.h).
#include "tactforce/planner/parameter_uncertainty.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include "absl/strings/match.h"
#include "absl/strings/str_cat.h"
#include "tactforce/planner/skew.h"
#include "tactforce/planner/validation.h"

namespace tactforce::planner {
namespace {

// L(v) with I_o v = L(v) (I_xx, I_yy, I_zz, I_xy, I_xz, I_yz).
Eigen::Matrix<double, 3, 6> InertiaProductMap(const Vec3& v) {
  Eigen::Matrix<double, 3, 6> l;
  l << v.x(), 0, 0, v.y(), v.z(), 0,  //
      0, v.y(), 0, v.x(), 0, v.z(),   //
      0, 0, v.z(), 0, v.x(), v.y();
  return l;
}

constexpr const char* kParameterNames[10] = {"m",   "m*cx", "m*cy", "m*cz", "Ixx",
                                             "Iyy", "Izz",  "Ixy",  "Ixz",  "Iyz"};

// Every entry +0 or -0 (Eigen's isZero(0.0)), column by column as one OR
// over the bits without the sign: cheap both on the plain path (a zero
// matrix) and on a covariance (out at its first column). A NaN is not zero.
bool IsZeroCovariance(const Matrix10d& s) {
  for (int j = 0; j < 10; ++j) {
    uint64_t bits = 0;
    for (int i = 0; i < 10; ++i) {
      uint64_t v;
      std::memcpy(&v, s.data() + 10 * j + i, sizeof v);
      bits |= v << 1;
    }
    if (bits != 0) return false;
  }
  return true;
}

// Largest |covariance| entry allowed: (kMaxInertia)^2, beyond any object.
constexpr double kMaxCovarianceEntry = kMaxInertia * kMaxInertia;

// True when an LDL^T of the symmetric s has only positive pivots, where a
// zero pivot is allowed when its whole remaining column is exactly zero (a
// parameter known exactly, e.g. the inertia in the mass-and-CoM short form):
// then s is PSD up to the factorisation's backward error (~1e-15 relative),
// far inside CheckCovariance's 1e-9. False means "not shown", not "not PSD".
bool LdltShowsPsd(const Matrix10d& s) {
  Matrix10d a = s;  // lower triangle: the working Schur complement
  for (int k = 0; k < 10; ++k) {
    const double pivot = a(k, k);
    if (!(pivot > 0.0)) {
      if (pivot != 0.0 || !a.col(k).tail(9 - k).isZero(0.0)) return false;
      continue;
    }
    for (int j = k + 1; j < 10; ++j) {
      const double l = a(j, k) / pivot;
      for (int i = j; i < 10; ++i) a(i, j) -= l * a(i, k);
    }
  }
  return true;
}

// Finite, within kMaxCovarianceEntry, symmetric (relative 1e-9), a
// non-negative diagonal and LdltShowsPsd: CheckCovariance would accept it.
bool PlainPsd(const Matrix10d& s) {
  if (!s.allFinite()) return false;
  const double scale = s.cwiseAbs().maxCoeff();
  if (scale > kMaxCovarianceEntry || s.diagonal().minCoeff() < 0.0) return false;
  double asymmetry = 0.0;
  for (int j = 0; j < 10; ++j) {
    for (int i = j + 1; i < 10; ++i) asymmetry = std::max(asymmetry, std::abs(s(i, j) - s(j, i)));
  }
  return asymmetry <= 1e-9 * scale && LdltShowsPsd(s);
}

}  // namespace

const char* ToString(UncertaintySource source) {
  switch (source) {
    case UncertaintySource::kNone:
      return "NONE";
    case UncertaintySource::kNominal:
      return "NOMINAL";
    case UncertaintySource::kMeasurement:
      return "MEASUREMENT";
    case UncertaintySource::kParameters:
      return "PARAMETERS";
    case UncertaintySource::kFriction:
      return "FRICTION";
    case UncertaintySource::kCombined:
      return "COMBINED";
  }
  return "UNKNOWN";
}

WrenchRegressorMatrix WrenchRegressor(const Vec3& gravity, const Motion& motion) {
  const Vec3 a_minus_g = motion.linear_acceleration - gravity;
  const Vec3& w = motion.angular_velocity;
  const Vec3& dw = motion.angular_acceleration;
  WrenchRegressorMatrix y = WrenchRegressorMatrix::Zero();
  y.block<3, 1>(0, 0) = a_minus_g;
  y.block<3, 3>(0, 1) = Skew(dw) + Skew(w) * Skew(w);
  y.block<3, 3>(3, 1) = -Skew(a_minus_g);
  y.block<3, 6>(3, 4) = InertiaProductMap(dw) + Skew(w) * InertiaProductMap(w);
  return y;
}

Vector10d StandardParameters(double mass, const Vec3& com, const Eigen::Matrix3d& inertia_com) {
  const Eigen::Matrix3d io = inertia_com + mass * (com.squaredNorm() * Eigen::Matrix3d::Identity() -
                                                   com * com.transpose());
  Vector10d pi;
  pi << mass, mass * com, io(0, 0), io(1, 1), io(2, 2), io(0, 1), io(0, 2), io(1, 2);
  return pi;
}

Matrix10d CovarianceFromMassAndCom(double mass, const Vec3& com, double mass_sigma,
                                   const Eigen::Matrix3d& com_covariance) {
  // d(m, h) = J (dm, dc), J = [1 0; c m I].
  Eigen::Matrix<double, 4, 4> j = Eigen::Matrix<double, 4, 4>::Zero();
  j(0, 0) = 1.0;
  j.block<3, 1>(1, 0) = com;
  j.block<3, 3>(1, 1) = mass * Eigen::Matrix3d::Identity();
  Eigen::Matrix<double, 4, 4> input = Eigen::Matrix<double, 4, 4>::Zero();
  input(0, 0) = mass_sigma * mass_sigma;
  input.block<3, 3>(1, 1) = 0.5 * (com_covariance + com_covariance.transpose());
  Matrix10d out = Matrix10d::Zero();
  out.topLeftCorner<4, 4>() = j * input * j.transpose();
  return out;
}

absl::Status CheckCovariance(absl::string_view field, const Eigen::MatrixXd& s, double limit,
                             const char* const* names) {
  const int n = static_cast<int>(s.rows());
  const auto entry = [&](int i, int j) { return absl::StrCat(field, "[", i * n + j, "]"); };
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      if (!std::isfinite(s(i, j)))
        return absl::InvalidArgumentError(entry(i, j) + ": not a finite number");
      if (std::abs(s(i, j)) > limit) {
        return absl::InvalidArgumentError(absl::StrCat(entry(i, j), ": magnitude exceeds ", limit));
      }
    }
  }
  const double scale = std::max(s.cwiseAbs().maxCoeff(), 1e-300);
  for (int i = 0; i < n; ++i) {
    for (int j = i + 1; j < n; ++j) {
      if (std::abs(s(i, j) - s(j, i)) > 1e-9 * scale) {
        return absl::InvalidArgumentError(absl::StrCat(entry(i, j), ": not symmetric (", s(i, j),
                                                       " but the entry [", j * n + i, "] is ",
                                                       s(j, i), ")"));
      }
    }
  }
  for (int i = 0; i < n; ++i) {
    if (s(i, i) < 0.0) return absl::InvalidArgumentError(entry(i, i) + ": negative variance");
  }
  // A pivoted LDL^T settles the common case cheaply (this runs on every
  // solve); only a failing or doubtful one pays for the eigenvalues.
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(s);
  if (ldlt.info() == Eigen::Success && ldlt.vectorD().minCoeff() >= 0.0) return absl::OkStatus();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(0.5 * (s + s.transpose()));
  if (eig.eigenvalues()(0) < -1e-9 * scale) {
    int k = 0;
    eig.eigenvectors().col(0).cwiseAbs().maxCoeff(&k);
    return absl::InvalidArgumentError(
        absl::StrCat(entry(k, k), ": not positive semidefinite (eigenvalue ", eig.eigenvalues()(0),
                     ", its direction mostly along index ", k,
                     names ? absl::StrCat(" (", names[k], ")") : "", ")"));
  }
  return absl::OkStatus();
}

absl::Status ValidateParameterUncertainty(const ParameterUncertainty& u) {
  if (u.confidence.has_value()) {
    const double k = *u.confidence;
    if (!std::isfinite(k) || k < 0.0 || k > PlanOptions::kMaxConfidence) {
      return absl::InvalidArgumentError(
          absl::StrCat("object.uncertainty.confidence: must be in [0, ",
                       PlanOptions::kMaxConfidence, "], got ", k));
    }
  }
  if (IsZeroCovariance(u.covariance)) return absl::OkStatus();
  // Fast path for the common valid case (this runs on every solve): a
  // fixed-size LDL^T that only accepts; anything doubtful goes to
  // CheckCovariance, which names the offending entry.
  if (PlainPsd(u.covariance)) return absl::OkStatus();
  return CheckCovariance("object.uncertainty.covariance", u.covariance, kMaxCovarianceEntry,
                         kParameterNames);
}

bool HasModelUncertainty(const PlanProblem& problem) {
  if (!IsZeroCovariance(problem.object.uncertainty.covariance)) return true;
  for (const Contact& c : problem.contacts) {
    if (c.friction_sigma > 0.0) return true;
  }
  return false;
}

void ApplyFrictionUncertainty(double confidence, PlanProblem* problem,
                              std::vector<double>* nominal_friction) {
  nominal_friction->clear();
  bool any = false;
  for (const Contact& c : problem->contacts) any = any || c.friction_sigma > 0.0;
  if (!any) return;
  for (Contact& c : problem->contacts) {
    nominal_friction->push_back(c.friction);
    if (c.friction_sigma > 0.0)
      c.friction = std::max(0.0, c.friction - confidence * c.friction_sigma);
    c.friction_sigma = 0.0;
  }
}

}  // namespace tactforce::planner

namespace tactforce::planner {
namespace {

using SmallMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, 6, 6>;

// Solves m z = b in place (b <- m^-1 b) by Gaussian elimination with
// partial pivoting, in fixed size: Eigen's PartialPivLU routes 6x6 solves
// through its blocked triangular kernels, several times this cost.
using RowMajor6d = Eigen::Matrix<double, 6, 6, Eigen::RowMajor>;

// Row-major, so each row operation is one contiguous vector operation.
template <int kCols>
void SolveSixInPlace(RowMajor6d m, Eigen::Matrix<double, 6, kCols, Eigen::RowMajor>* b) {
  for (int k = 0; k < 6; ++k) {
    int p = k;
    for (int i = k + 1; i < 6; ++i) {
      if (std::abs(m(i, k)) > std::abs(m(p, k))) p = i;
    }
    if (p != k) {
      m.row(p).swap(m.row(k));
      b->row(p).swap(b->row(k));
    }
    for (int i = k + 1; i < 6; ++i) {
      const double l = m(i, k) / m(k, k);
      for (int j = k + 1; j < 6; ++j) m(i, j) -= l * m(k, j);
      b->row(i) -= l * b->row(k);
    }
  }
  for (int k = 5; k >= 0; --k) {
    for (int j = k + 1; j < 6; ++j) b->row(k) -= m(k, j) * b->row(j);
    b->row(k) /= m(k, k);
  }
}

// With U the orthonormal rows spanning G's row space (r x 3n) and M = G U^T
// (6 x r, full column rank), G^+ = U^T X with X = (M^T M)^-1 M^T, so
// P_i = (G^+ S_b G^+T)_ii = U_i^T (X S_b X^T) U_i.
//
// Full rank (r = 6, every grasp that resists all wrenches): M is square and
// X = M^-1, so with Z = M^-1 Y (one solve) and V_i = U_i^T Z (3 x 10),
// P_i = V_i S_pi V_i^T; neither S_b nor the 6x6 X S_b X^T is formed. `y`
// holds Y's first kParams columns, the rest being zero (4: no rotation, where
// the inertia does not enter the wrench). All in fixed sizes, M's columns
// from G's structure.
template <int kParams>
void ContactCovariancesFullRank(const ForceEquilibrium& eq,
                                const Eigen::Matrix<double, 6, kParams>& y,
                                const Matrix10d& covariance, std::vector<Eigen::Matrix3d>* out) {
  const int n = static_cast<int>(eq.grasp_matrix.cols() / 3);
  const Eigen::Matrix<double, kParams, kParams> s = covariance.topLeftCorner<kParams, kParams>();
  RowMajor6d m = RowMajor6d::Zero();
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 6, 3> u = eq.independent_rows.middleCols<3>(3 * i);  // 6 x 3
    const Eigen::Matrix3d skew = eq.grasp_matrix.block<3, 3>(3, 3 * i);
    m.topRows<3>().noalias() += u.transpose();
    m.bottomRows<3>().noalias() += skew.lazyProduct(u.transpose());
  }
  Eigen::Matrix<double, 6, kParams, Eigen::RowMajor> z = y;
  SolveSixInPlace(m, &z);
  out->resize(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Matrix<double, 6, 3> u = eq.independent_rows.middleCols<3>(3 * i);
    const Eigen::Matrix<double, 3, kParams> v = u.transpose().lazyProduct(z);
    const Eigen::Matrix<double, 3, kParams> vs = v.lazyProduct(s);
    (*out)[i] = vs.lazyProduct(v.transpose());
  }
}

// The general case (any rank r < 6). Returns the size (N, N m) of the part
// of the kappa_b wrench ellipsoid no contact force can balance:
// sqrt(lambda_max((I - M X) S_b (I - M X)^T)).
double ContactCovariances(const ForceEquilibrium& eq, const Eigen::Matrix<double, 6, 6>& wrench_cov,
                          std::vector<Eigen::Matrix3d>* out) {
  const int n = static_cast<int>(eq.grasp_matrix.cols() / 3);
  const int r = static_cast<int>(eq.independent_rows.rows());
  const SmallMatrix m = eq.grasp_matrix * eq.independent_rows.transpose();  // 6 x r
  const SmallMatrix normal = m.transpose() * m;
  const SmallMatrix x = normal.llt().solve(m.transpose());  // r x 6
  const SmallMatrix k = x * wrench_cov * x.transpose();     // r x r
  out->resize(n);
  for (int i = 0; i < n; ++i) {
    const auto u = eq.independent_rows.middleCols<3>(3 * i);  // r x 3
    (*out)[i].noalias() = u.transpose() * k * u;
  }
  if (r >= 6) return 0.0;
  const Eigen::Matrix<double, 6, 6> reject = Eigen::Matrix<double, 6, 6>::Identity() - m * x;
  const Eigen::Matrix<double, 6, 6> rest = reject * wrench_cov * reject.transpose();
  return std::sqrt(std::max(
      0.0, Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>>(rest, Eigen::EigenvaluesOnly)
               .eigenvalues()(5)));
}

// Every P_i; marks the equilibrium inconsistent when some wrench in
// the kappa_b ellipsoid cannot be balanced by any contact force.
void ParameterCovariances(const PlanProblem& problem, ForceEquilibrium* eq,
                          ParameterTightening* t) {
  const Matrix10d& covariance = problem.object.uncertainty.covariance;
  const Motion& motion = problem.motion;
  if (eq->independent_rows.rows() == 6 && motion.angular_velocity.isZero(0.0) &&
      motion.angular_acceleration.isZero(0.0)) {
    // Without rotation Y = [a - g, 0, 0; 0, -[a - g]x, 0] (WrenchRegressor):
    // only the mass and the first moment enter.
    const Vec3 a_minus_g = motion.linear_acceleration - problem.object.gravity;
    Eigen::Matrix<double, 6, 4> y = Eigen::Matrix<double, 6, 4>::Zero();
    y.block<3, 1>(0, 0) = a_minus_g;
    y.block<3, 3>(3, 1) = -Skew(a_minus_g);
    ContactCovariancesFullRank<4>(*eq, y, covariance, &t->contact_covariance);
    return;
  }
  const WrenchRegressorMatrix y = WrenchRegressor(problem.object.gravity, motion);
  if (eq->independent_rows.rows() == 6) {
    ContactCovariancesFullRank<10>(*eq, y, covariance, &t->contact_covariance);
    return;
  }
  // Coefficient-based products: at these sizes Eigen's GEMM path costs more
  // than the arithmetic.
  const Eigen::Matrix<double, 6, 10> ys = y.lazyProduct(covariance);
  const Eigen::Matrix<double, 6, 6> wrench_covariance = ys.lazyProduct(y.transpose());  // S_b
  const double unbalanced = ContactCovariances(*eq, wrench_covariance, &t->contact_covariance);
  if (t->confidence * unbalanced > 1e-8 * std::max(1.0, eq->wrench.norm())) {
    eq->consistent = false;
    eq->residual = std::max(eq->residual, t->confidence * unbalanced);
  }
}

}  // namespace

void TightenForParameters(const PlanOptions& options, PreparedProblem* p) {
  ParameterTightening& t = p->parameters;
  const ParameterUncertainty& u = p->problem.object.uncertainty;
  t.confidence = u.confidence.value_or(options.confidence);
  t.active = t.confidence > 0.0 && !IsZeroCovariance(u.covariance);
  t.cone_margin.clear();
  if (!t.active) {
    t.contact_covariance.clear();
    t.row_margin.resize(0);
    return;
  }
  ParameterCovariances(p->problem, &p->equilibrium, &t);
  ConstraintRows& rows = p->rows;
  const int m = static_cast<int>(rows.info.size());
  t.row_margin.resize(m);
  // Locals, so the stores do not force every read to be redone.
  const double kappa_b = t.confidence;
  const RowInfo* info = rows.info.data();
  const Eigen::Matrix3d* covariance = t.contact_covariance.data();
  double* margin = t.row_margin.data();
  double* rhs = rows.rhs.data();
  for (int r = 0; r < m; ++r) {
    const int c = info[r].contact;
    const Vec3 a = rows.directions.row(r).transpose();
    margin[r] = kappa_b * std::sqrt(std::max(0.0, a.dot(covariance[c] * a)));
    rhs[r] -= margin[r];
  }
  if (p->cone_shift.empty()) return;
  t.cone_margin.resize(p->cone_shift.size());
  for (int i = 0; i < p->num_contacts(); ++i) {
    const Contact& c = p->problem.contacts[i];
    const Eigen::Matrix3d& s = t.contact_covariance[i];
    const double normal_spread = std::sqrt(std::max(0.0, c.normal.dot(s * c.normal)));
    t.cone_margin[i] = t.confidence * (c.friction * normal_spread + TangentialSpread(c.normal, s));
    p->cone_shift[i] += t.cone_margin[i];
  }
}

}  // namespace tactforce::planner

namespace tactforce::planner {

void FillRowMargins(const PreparedProblem& prepared, const std::vector<Vec3>& forces,
                    std::vector<RowMargin>* out) {
  const ConstraintRows& rows = prepared.rows;
  const ParameterTightening& t = prepared.parameters;
  const int m = static_cast<int>(rows.info.size());
  const bool have_forces = static_cast<int>(forces.size()) == prepared.num_contacts();
  out->resize(m + prepared.cone_shift.size());
  // Locals, so the stores into `out` do not force every read to be redone.
  RowMargin* o = out->data();
  const RowInfo* info = rows.info.data();
  const double* rhs = rows.rhs.data();
  const double* nominal = rows.nominal_rhs.data();
  const double* parameters = t.active ? t.row_margin.data() : nullptr;
  for (int r = 0; r < m; ++r) {
    const int c = info[r].contact;
    const RowKind kind = info[r].kind;
    const double part = parameters ? parameters[r] : 0.0;
    const double slack =
        have_forces ? rhs[r] - rows.directions.row(r).dot(forces[c].transpose()) : 0.0;
    o[r] = RowMargin{c,
                     false,
                     r,
                     kind == RowKind::kFrictionFacet ? info[r].facet : -1,
                     kind == RowKind::kMaxNormal,
                     slack,
                     std::max(0.0, nominal[r] - rhs[r] - part),
                     part};
  }
  for (int i = 0; i < static_cast<int>(prepared.cone_shift.size()); ++i) {
    RowMargin& o = (*out)[m + i];
    const Contact& c = prepared.problem.contacts[i];
    o.contact = i, o.cone = true, o.row = -1, o.slack = 0.0, o.facet = -1, o.upper = false;
    o.parameters = t.active ? t.cone_margin[i] : 0.0;
    o.measurement = std::max(0.0, prepared.cone_shift[i] - o.parameters);
    if (have_forces)
      o.slack = ExactConeSlack(c.normal, c.friction, prepared.cone_shift[i], forces[i]);
  }
}

}  // namespace tactforce::planner
