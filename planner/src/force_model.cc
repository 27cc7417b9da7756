// The shared geometry of force_model.h: G and b, the FE-plane, the measurement
// ellipsoid, the tightened rows and cones, and Prepare().
#include "tactforce/planner/force_model.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <tuple>

#include <Eigen/SVD>
#include <emmintrin.h>

#include "absl/strings/str_cat.h"
#include "tactforce/planner/parameter_uncertainty.h"
#include "tactforce/planner/skew.h"

namespace tactforce::planner {
namespace {

// Householder QR in place: `a` (rows x cols, rows >= cols or not) becomes R
// in its upper part; reflector k (unit, zero above row k) goes to
// reflectors.col(k), a zero column meaning "no reflection". Then Q = H_0 ...
// H_{c-1} is accumulated into `q` (rows x rows).
// y -= 2 (v . y) v over `length` contiguous entries, two lanes at a time
// (SSE2, part of x86-64): the dot product keeps two chains, even and odd
// entries, summed at the end, so the result does not depend on the width.
inline void Reflect(const double* __restrict v, double* __restrict y, int length) {
  __m128d dots = _mm_setzero_pd();  // (even chain, odd chain)
  int r = 0;
  for (; r + 1 < length; r += 2) {
    dots = _mm_add_pd(dots, _mm_mul_pd(_mm_loadu_pd(v + r), _mm_loadu_pd(y + r)));
  }
  double dot0 = _mm_cvtsd_f64(dots);
  const double dot1 = _mm_cvtsd_f64(_mm_unpackhi_pd(dots, dots));
  if (r < length) dot0 += v[r] * y[r];
  const double scale = 2.0 * (dot0 + dot1);
  const __m128d scales = _mm_set1_pd(scale);
  for (r = 0; r + 1 < length; r += 2) {
    _mm_storeu_pd(y + r, _mm_sub_pd(_mm_loadu_pd(y + r), _mm_mul_pd(scales, _mm_loadu_pd(v + r))));
  }
  if (r < length) y[r] -= scale * v[r];
}

// Written out rather than Eigen::HouseholderQR because forming Q through
// Eigen's public API (householderQ() into a matrix) allocates a workspace on
// every call, and the planning workspace must not allocate once warm.
void HouseholderQr(MatrixXd& a, MatrixXd& reflectors, MatrixXd& q) {
  const int rows = static_cast<int>(a.rows());
  const int cols = static_cast<int>(a.cols());
  const int steps = std::min(rows, cols);
  reflectors.resize(rows, cols);
  for (int k = 0; k < steps; ++k) {
    double* v = reflectors.col(k).data() + k;
    const double* x = a.col(k).data() + k;
    double norm2 = 0.0;
    for (int r = 0; r < rows - k; ++r) norm2 += x[r] * x[r];
    const double norm = std::sqrt(norm2);
    if (norm == 0.0) {  // nothing to reflect: mark with a zero vector
      std::fill(v, v + rows - k, 0.0);
      continue;
    }
    std::copy(x, x + rows - k, v);
    // v = x - alpha e1, alpha = -sign(x0) |x|, then normalised.
    const double v0 = v[0] + (v[0] >= 0.0 ? norm : -norm);
    const double v_norm = std::sqrt(norm2 - v[0] * v[0] + v0 * v0);
    v[0] = v0;
    for (int r = 0; r < rows - k; ++r) v[r] /= v_norm;
    for (int j = k; j < cols; ++j) Reflect(v, a.col(j).data() + k, rows - k);
  }
  q.setIdentity(rows, rows);
  for (int k = steps - 1; k >= 0; --k) {
    const double* v = reflectors.col(k).data() + k;  // zero: reflects nothing
    for (int j = k; j < rows; ++j) Reflect(v, q.col(j).data() + k, rows - k);
  }
}

// Fills b and, with `grasp_matrix`, G (6 x 3n; else G is left empty).
void FillGraspMatrixAndWrench(const PlanProblem& problem, bool grasp_matrix, ForceEquilibrium* eq) {
  const int n = grasp_matrix ? static_cast<int>(problem.contacts.size()) : 0;
  eq->grasp_matrix.resize(grasp_matrix ? 6 : 0, 3 * n);
  for (int i = 0; i < n; ++i) {
    eq->grasp_matrix.block<3, 3>(0, 3 * i).setIdentity();
    eq->grasp_matrix.block<3, 3>(3, 3 * i) = Skew(problem.contacts[i].position);
  }
  const ObjectModel& o = problem.object;
  const Vec3 weight = o.mass * o.gravity;
  eq->wrench.head<3>() = -(weight + problem.external_wrench.force);
  eq->wrench.tail<3>() = -(o.com.cross(weight) + problem.external_wrench.torque);
}

// |G f - b| from the structure of G (sum of forces, sum of moments).
double EquilibriumResidual(const PlanProblem& problem, const VectorXd& f, const Vector6d& b) {
  Vec3 force = -b.head<3>();
  Vec3 torque = -b.tail<3>();
  for (int i = 0; i < static_cast<int>(problem.contacts.size()); ++i) {
    const Vec3 fi = f.segment<3>(3 * i);
    force += fi;
    torque += problem.contacts[i].position.cross(fi);
  }
  return std::sqrt(force.squaredNorm() + torque.squaredNorm());
}

// H x I3 with H = I - 2 v v^T (n x n), v = (e_1 + u) / |e_1 + u|, u = 1 /
// sqrt(n): H e_1 = -u, so the first three columns of H x I3 span the force
// columns F = [I; ...; I] of G_c^T and the rest their complement, with no
// factorisation. Applied in place to a 3n vector (contact-major).
class ContactMixer {
 public:
  explicit ContactMixer(int n) : n_(n) {
    const double u = 1.0 / std::sqrt(double(n));
    const double norm = std::sqrt(2.0 + 2.0 * u);
    first_ = (1.0 + u) / norm;
    other_ = u / norm;
  }
  // The three components at once (each summed in contact order, as one
  // component at a time would).
  void Apply(double* x) const {
    Eigen::Map<Vec3> head(x);
    Vec3 others = Vec3::Zero();
    for (int i = 1; i < n_; ++i) others += Eigen::Map<const Vec3>(x + 3 * i);
    const Vec3 scale = 2.0 * (first_ * head + other_ * others);
    head -= scale * first_;
    const Vec3 step = scale * other_;
    for (int i = 1; i < n_; ++i) Eigen::Map<Vec3>(x + 3 * i) -= step;
  }

 private:
  int n_;
  double first_ = 0.0, other_ = 0.0;  // v_1 and v_i (i > 1)
};

// Whether the upper triangular R_t's three singular values all exceed the
// rank cut-off rank_tolerance * max(1, sqrt(n), sigma_1), decided from
// bounds: sigma_3 >= |det R| / (sigma_1 sigma_2) >= 2 |det R| / |R|_F^2 and
// sigma_1 <= |R|_F. Only when the bounds do not decide is the SVD needed.
bool ClearlyFullRank(const Eigen::Matrix3d& r, double rank_tolerance, int n) {
  const double frobenius2 = r.squaredNorm();
  if (!(frobenius2 > 0.0)) return false;
  const double det = std::abs(r(0, 0) * r(1, 1) * r(2, 2));
  const double cutoff =
      rank_tolerance * std::max({1.0, std::sqrt(double(n)), std::sqrt(frobenius2)});
  return 2.0 * det / frobenius2 > cutoff;
}

// The torque block R_t (upper triangular, the first 3 rows of `reduced`)
// and its rank: from bounds when clearly full (no SVD, U = W = I), else from
// its SVD R_t = U S W^T.
struct TorqueRange {
  TorqueRange(const MatrixXd& reduced, bool has_block, double rank_tolerance, int n) {
    if (!has_block) return;
    r = reduced.topRows<3>().triangularView<Eigen::Upper>();
    if (ClearlyFullRank(r, rank_tolerance, n)) {
      rank = 3;
      return;
    }
    RankFromSvd(rank_tolerance, n);
  }
  // The rare path (collinear or coincident contacts), out of line. GCC 12
  // warns, wrongly, that the fixed-size SVD's singular values may be used
  // uninitialised once it is inlined here.
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
  [[gnu::noinline]] void RankFromSvd(double rank_tolerance, int n) {
    svd_used = true;
    const Eigen::JacobiSVD<Eigen::Matrix3d> svd(r, Eigen::ComputeFullU | Eigen::ComputeFullV);
    u = svd.matrixU();
    w = svd.matrixV();
    s = svd.singularValues();
    const double cutoff = rank_tolerance * std::max({1.0, std::sqrt(double(n)), s(0)});
    while (rank < 3 && s(rank) > cutoff) ++rank;
  }
#pragma GCC diagnostic pop
  Eigen::Matrix3d r = Eigen::Matrix3d::Zero();
  Eigen::Matrix3d u = Eigen::Matrix3d::Identity();
  Eigen::Matrix3d w = Eigen::Matrix3d::Identity();
  Vec3 s = Vec3::Zero();
  int rank = 0;
  bool svd_used = false;
};

// f0 = Q_f y_f + Q_t y_t from R^T y = b_c (minimum norm): Q_f y_f puts
// b_f / n on every contact; R_t^T y_t = b_c,t = b_t - c x b_f (through the
// SVD's pseudo-inverse when it was needed).
void ParticularSolution(const Vec3& centroid, const TorqueRange& torque, const MatrixXd& q_torque,
                        ForceEquilibrium* eq) {
  const int dim = static_cast<int>(q_torque.rows());
  const int n = dim / 3;
  const Vec3 b_force = eq->wrench.head<3>();
  const Vec3 b_torque = eq->wrench.tail<3>() - centroid.cross(b_force);
  eq->particular.resize(dim);
  for (int i = 0; i < n; ++i) eq->particular.segment<3>(3 * i) = b_force / n;
  if (torque.rank == 0) return;
  Vec3 y_torque = Vec3::Zero();
  if (torque.svd_used) {
    for (int k = 0; k < torque.rank; ++k) {
      y_torque += (torque.w.col(k).dot(b_torque) / torque.s(k)) * torque.u.col(k);
    }
  } else {
    y_torque = torque.r.transpose().triangularView<Eigen::Lower>().solve(b_torque);
  }
  eq->particular.noalias() += q_torque * y_torque;
}

// The independent rows [Q_f^T; U_r^T Q_t^T] (rank x 3n) and their right-hand
// side rows f0; with `range_rows` false both are left empty.
void FillIndependentRows(const TorqueRange& torque, const MatrixXd& q_torque, bool range_rows,
                         ForceEquilibrium* eq) {
  const int dim = range_rows ? static_cast<int>(q_torque.rows()) : 0;
  eq->independent_rows.setZero(range_rows ? eq->rank : 0, dim);
  if (!range_rows) {
    eq->independent_rhs.resize(0);
    return;
  }
  const double force_entry = -1.0 / std::sqrt(double(dim / 3));
  for (int j = 0; j < dim; ++j) eq->independent_rows(j % 3, j) = force_entry;
  if (torque.svd_used) {
    eq->independent_rows.bottomRows(torque.rank).noalias() =
        torque.u.leftCols(torque.rank).transpose() * q_torque.transpose();
  } else if (torque.rank == 3) {
    eq->independent_rows.bottomRows<3>() = q_torque.transpose();
  }
  eq->independent_rhs.noalias() = eq->independent_rows * eq->particular;
}

}  // namespace

void ComputeForceEquilibrium(const PlanProblem& problem, double rank_tolerance,
                             EquilibriumScratch* scratch, ForceEquilibrium* eq, bool range_rows) {
  const int n = static_cast<int>(problem.contacts.size());
  const int dim = 3 * n;
  FillGraspMatrixAndWrench(problem, range_rows, eq);
  Vec3 centroid = Vec3::Zero();
  for (const Contact& c : problem.contacts) centroid += c.position;
  centroid /= n;
  const ContactMixer mixer(n);

  // Q_f = (H x I3) e_k = -F / sqrt(n), R_f = -sqrt(n) I. The torque columns
  // T (rows [p_i - c]x^T) are orthogonal to F, so (H x I3) T = [0; T''] and
  // the QR of T'' (3(n-1) x 3) gives R_t and Q'' = [Q''_t | Q''_rest].
  const bool has_torque_block = n >= 2;
  MatrixXd& torque = scratch->reflected;
  torque.resize(dim, 3);
  for (int i = 0; i < n; ++i) {
    torque.block<3, 3>(3 * i, 0) = Skew(problem.contacts[i].position - centroid).transpose();
  }
  for (int k = 0; k < 3; ++k) mixer.Apply(torque.col(k).data());
  MatrixXd& reduced = scratch->reduced;
  reduced = torque.bottomRows(dim - 3);
  HouseholderQr(reduced, scratch->reflectors, scratch->orthogonal);
  const MatrixXd& q = scratch->orthogonal;  // Q'' (3(n-1) square)

  // Rank: the force block always has rank 3 (singular values sqrt(n)).
  const TorqueRange torque_range(reduced, has_torque_block, rank_tolerance, n);
  const int torque_rank = torque_range.rank;
  const bool svd_used = torque_range.svd_used;
  const Eigen::Matrix3d& torque_u = torque_range.u;
  eq->rank = 3 + torque_rank;

  // Q_t = (H x I3) [0; Q''_t] (3n x 3): the torque range columns, and with
  // the SVD, rotated into U (range U_r, lost U_lost).
  MatrixXd& q_torque = scratch->torque_basis;
  q_torque.setZero(dim, 3);
  if (has_torque_block) {
    q_torque.bottomRows(dim - 3) = q.leftCols<3>();
    for (int k = 0; k < 3; ++k) mixer.Apply(q_torque.col(k).data());
  }
  const int lost = has_torque_block ? 3 - torque_rank : 0;
  const int rest = has_torque_block ? dim - 6 : dim - 3;
  eq->null_basis.resize(dim, lost + rest);
  if (svd_used) eq->null_basis.leftCols(lost).noalias() = q_torque * torque_u.rightCols(lost);
  for (int j = 0; j < rest; ++j) {
    double* column = eq->null_basis.col(lost + j).data();
    std::fill(column, column + 3, 0.0);
    const double* source = q.col((has_torque_block ? 3 : 0) + j).data();
    std::copy(source, source + dim - 3, column + 3);
    mixer.Apply(column);
  }

  ParticularSolution(centroid, torque_range, scratch->torque_basis, eq);
  FillIndependentRows(torque_range, q_torque, range_rows, eq);
  eq->residual = EquilibriumResidual(problem, eq->particular, eq->wrench);
  eq->consistent = eq->residual <= 1e-8 * std::max(1.0, eq->wrench.norm());
}

ForceEquilibrium ComputeForceEquilibrium(const PlanProblem& problem, double rank_tolerance) {
  EquilibriumScratch scratch;
  ForceEquilibrium eq;
  ComputeForceEquilibrium(problem, rank_tolerance, &scratch, &eq);
  return eq;
}

double MeasurementEllipsoid::Support(const VectorXd& a) const {
  return factor.cols() == 0 ? 0.0 : (factor.transpose() * a).norm();
}

void ComputeMeasurementEllipsoid(const PlanProblem& problem, const ForceEquilibrium& eq,
                                 MeasurementEllipsoid* out) {
  const int n = static_cast<int>(problem.contacts.size());
  const auto noisy = [](const Contact& c) {
    return c.kind == ContactKind::kIntrinsic && c.sigma > 0.0;
  };
  int count = 0;
  for (const Contact& c : problem.contacts) count += noisy(c) ? 1 : 0;
  const int d = static_cast<int>(eq.null_basis.cols());
  if (count == 0 || d == 0) count = 0;
  // E diag(sigma) = B^T N_I diag(sigma): one column per intrinsic contact
  // with sigma > 0, from that contact's three rows of B.
  // Raw loops, each sum in the order of Eigen's products: an entry of B_i^T v
  // as (b_0 v_0 + b_1 v_1) + b_2 v_2, one of B E over k in turn.
  const int dim = 3 * n;
  const double* basis = eq.null_basis.data();  // column k at basis + k dim
  out->plane_factor.resize(d, count);
  for (int i = 0, j = 0; i < n && j < count; ++i) {
    const Contact& c = problem.contacts[i];
    if (!noisy(c)) continue;
    const Vec3 v = c.sigma * c.normal;
    double* e = out->plane_factor.col(j++).data();
    for (int k = 0; k < d; ++k) {
      const double* b = basis + k * dim + 3 * i;
      e[k] = b[0] * v(0) + b[1] * v(1) + b[2] * v(2);
    }
  }
  // L = B E diag(sigma): the FE-plane projection of the reading noise, two
  // rows at a time with the running sums in registers.
  out->factor.resize(dim, count);
  for (int j = 0; j < count; ++j) {
    double* l = out->factor.col(j).data();
    const double* e = out->plane_factor.col(j).data();
    int r = 0;
    for (; r + 1 < dim; r += 2) {
      __m128d sum = _mm_mul_pd(_mm_loadu_pd(basis + r), _mm_set1_pd(e[0]));
      for (int k = 1; k < d; ++k) {
        sum = _mm_add_pd(sum, _mm_mul_pd(_mm_loadu_pd(basis + k * dim + r), _mm_set1_pd(e[k])));
      }
      _mm_storeu_pd(l + r, sum);
    }
    for (; r < dim; ++r) {
      double sum = basis[r] * e[0];
      for (int k = 1; k < d; ++k) sum += basis[k * dim + r] * e[k];
      l[r] = sum;
    }
  }
  // S_ii as the sum of l l^T over the factor's columns (a few 3-vectors):
  // cheaper than a general product of a 3 x k block with its transpose.
  out->contact_covariance.resize(n);
  for (int i = 0; i < n; ++i) {
    Eigen::Matrix3d& s = out->contact_covariance[i];
    s.setZero();
    for (int j = 0; j < count; ++j) {
      const Vec3 l = out->factor.col(j).segment<3>(3 * i);
      s.noalias() += l * l.transpose();
    }
  }
}

MeasurementEllipsoid ComputeMeasurementEllipsoid(const PlanProblem& problem,
                                                 const ForceEquilibrium& eq) {
  MeasurementEllipsoid ellipsoid;
  ComputeMeasurementEllipsoid(problem, eq, &ellipsoid);
  return ellipsoid;
}

std::pair<Vec3, Vec3> TangentBasis(const Vec3& normal) {
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(normal(k)) < std::abs(normal(axis))) axis = k;
  }
  const Vec3 e = Vec3::Unit(axis);
  const Vec3 t1 = (e - e.dot(normal) * normal).normalized();
  return {t1, normal.cross(t1)};
}

std::string ContactLabel(const PlanProblem& problem, int contact) {
  std::string label = absl::StrCat("contact ", contact);
  const std::string& name = problem.contacts[contact].name;
  if (!name.empty()) absl::StrAppend(&label, " (", name, ")");
  return label;
}

std::string ConstraintRows::Describe(int row, const PlanProblem& problem) const {
  if (row < 0 || row >= static_cast<int>(info.size())) return absl::StrCat("row ", row);
  const RowInfo& r = info[row];
  const std::string who = ContactLabel(problem, r.contact);
  switch (r.kind) {
    case RowKind::kFrictionFacet:
      return absl::StrCat(who, " friction cone facet ", r.facet);
    case RowKind::kMinNormal:
      return absl::StrCat(who, " minimum normal force");
    case RowKind::kMaxNormal:
      return absl::StrCat(who, " maximum normal force");
  }
  return who;
}

namespace {

// cos and sin of 2 pi j / k for every k in kMinConeSides..kMaxConeSides,
// built once: no trigonometry per request.
struct FacetTable {
  std::vector<double> cos_theta, sin_theta;
  std::vector<int> offset;  // first entry of k
  FacetTable() {
    offset.assign(PlanOptions::kMaxConeSides + 1, 0);
    for (int k = PlanOptions::kMinConeSides; k <= PlanOptions::kMaxConeSides; ++k) {
      offset[k] = static_cast<int>(cos_theta.size());
      for (int j = 0; j < k; ++j) {
        const double theta = 2.0 * std::numbers::pi * j / k;
        cos_theta.push_back(std::cos(theta));
        sin_theta.push_back(std::sin(theta));
      }
    }
  }
};

const FacetTable& Facets() {
  static const FacetTable* table = new FacetTable();
  return *table;
}

// cos and sin of 2 pi j / K, j < K: the table's, or (K out of its range)
// computed into `own`.
std::pair<const double*, const double*> FacetAngles(int cone_sides, std::vector<double>* own) {
  if (cone_sides >= PlanOptions::kMinConeSides && cone_sides <= PlanOptions::kMaxConeSides) {
    const FacetTable& facets = Facets();
    return {facets.cos_theta.data() + facets.offset[cone_sides],
            facets.sin_theta.data() + facets.offset[cone_sides]};
  }
  own->resize(2 * std::max(cone_sides, 0));
  for (int j = 0; j < cone_sides; ++j) {
    const double theta = 2.0 * std::numbers::pi * j / cone_sides;
    (*own)[j] = std::cos(theta);
    (*own)[cone_sides + j] = std::sin(theta);
  }
  return {own->data(), own->data() + std::max(cone_sides, 0)};
}

}  // namespace

MatrixXd ConstraintRows::Dense(int num_contacts) const {
  MatrixXd a = MatrixXd::Zero(static_cast<Eigen::Index>(info.size()), 3 * num_contacts);
  for (int r = 0; r < static_cast<int>(info.size()); ++r) {
    a.block<1, 3>(r, 3 * info[r].contact) = directions.row(r);
  }
  return a;
}

namespace {

// Largest eigenvalue's root of the 2x2 form [a b; b c] (the covariance in
// the tangent plane): TangentialSpread from the forms it is made of.
double SpreadOfForms(double a, double b, double c) {
  const double lambda_max = 0.5 * (a + c) + std::hypot(0.5 * (a - c), b);
  return std::sqrt(std::max(0.0, lambda_max));
}

// One contact's pyramid facets a_j = co_j t1 + si_j t2 - k n, j < count,
// stored from row 0 of the given columns: nominal 0, robust 0 - kappa
// sqrt(max(0, a_j^T S a_j)), the quadratic from the contact's six forms of
// S. Two facets per SSE2 instruction, each lane the scalar expression in the
// same order (so the rows do not depend on the pairing).
struct FacetForms {
  Vec3 t1, t2, normal;
  double k = 0.0;  // mu cos(pi / K)
  double s11 = 0.0, s22 = 0.0, s12 = 0.0, s1n = 0.0, s2n = 0.0, snn = 0.0;
};

void FacetRows(const FacetForms& f, const double* co, const double* si, int count,
               double confidence, double* dx, double* dy, double* dz, double* nominal,
               double* rhs) {
  const double two_k = 2.0 * f.k, kk_snn = f.k * f.k * f.snn;
  const Vec3 kn = f.k * f.normal;
  const auto row = [&](double c, double s, int j) {
    const double quadratic = c * c * f.s11 + s * s * f.s22 + 2.0 * c * s * f.s12 -
                             two_k * (c * f.s1n + s * f.s2n) + kk_snn;
    dx[j] = c * f.t1(0) + s * f.t2(0) - kn(0);
    dy[j] = c * f.t1(1) + s * f.t2(1) - kn(1);
    dz[j] = c * f.t1(2) + s * f.t2(2) - kn(2);
    nominal[j] = 0.0;
    rhs[j] = 0.0 - confidence * std::sqrt(std::max(0.0, quadratic));
  };
  const __m128d zero = _mm_setzero_pd(), two = _mm_set1_pd(2.0);
  const __m128d s11 = _mm_set1_pd(f.s11), s22 = _mm_set1_pd(f.s22), s12 = _mm_set1_pd(f.s12);
  const __m128d s1n = _mm_set1_pd(f.s1n), s2n = _mm_set1_pd(f.s2n);
  const __m128d twok = _mm_set1_pd(two_k), kksnn = _mm_set1_pd(kk_snn);
  const __m128d kappa = _mm_set1_pd(confidence);
  const auto axis = [](__m128d c, __m128d s, double t1, double t2, double kn) {
    return _mm_sub_pd(_mm_add_pd(_mm_mul_pd(c, _mm_set1_pd(t1)), _mm_mul_pd(s, _mm_set1_pd(t2))),
                      _mm_set1_pd(kn));
  };
  int j = 0;
  for (; j + 1 < count; j += 2) {
    const __m128d c = _mm_loadu_pd(co + j), s = _mm_loadu_pd(si + j);
    __m128d q = _mm_add_pd(_mm_mul_pd(_mm_mul_pd(c, c), s11), _mm_mul_pd(_mm_mul_pd(s, s), s22));
    q = _mm_add_pd(q, _mm_mul_pd(_mm_mul_pd(_mm_mul_pd(two, c), s), s12));
    q = _mm_sub_pd(q, _mm_mul_pd(twok, _mm_add_pd(_mm_mul_pd(c, s1n), _mm_mul_pd(s, s2n))));
    q = _mm_add_pd(q, kksnn);
    // max(q, 0) is 0 for a NaN q, as std::max(0.0, q).
    const __m128d support = _mm_sqrt_pd(_mm_max_pd(q, zero));
    _mm_storeu_pd(rhs + j, _mm_sub_pd(zero, _mm_mul_pd(kappa, support)));
    _mm_storeu_pd(nominal + j, zero);
    _mm_storeu_pd(dx + j, axis(c, s, f.t1(0), f.t2(0), kn(0)));
    _mm_storeu_pd(dy + j, axis(c, s, f.t1(1), f.t2(1), kn(1)));
    _mm_storeu_pd(dz + j, axis(c, s, f.t1(2), f.t2(2), kn(2)));
  }
  if (j < count) row(co[j], si[j], j);
}

// BuildConstraintRows; with `normal_sigma` given and the facets' quadratic
// forms of S_ii formed (confidence > 0, facets), also the per-contact sigmas
// from those same forms (the tangential ones when `tangential_sigma` is
// given too), and returns true.
bool BuildRows(const PlanProblem& problem, const MeasurementEllipsoid& ellipsoid, int cone_sides,
               double confidence, bool with_friction_facets, ConstraintRows* out,
               std::vector<double>* normal_sigma, std::vector<double>* tangential_sigma) {
  const int n = static_cast<int>(problem.contacts.size());
  int m = 0;
  for (const Contact& c : problem.contacts) {
    m += (with_friction_facets ? cone_sides : 0) + 1 + (c.max_normal_force > 0.0 ? 1 : 0);
  }
  ConstraintRows& rows = *out;
  rows.directions.resize(m, 3);
  rows.rhs.resize(m);
  rows.nominal_rhs.resize(m);
  rows.info.resize(m);
  rows.contact_first.resize(n + 1);
  std::vector<double> own;  // only for a cone_sides outside the table's range
  const auto [cos_theta, sin_theta] = with_friction_facets
                                          ? FacetAngles(cone_sides, &own)
                                          : std::pair<const double*, const double*>();
  const double cos_half = std::cos(std::numbers::pi / cone_sides);
  // Raw column pointers: no per-call bookkeeping of Eigen's in the row loop.
  double* const dx = rows.directions.col(0).data();
  double* const dy = rows.directions.col(1).data();
  double* const dz = rows.directions.col(2).data();
  double* const rhs = rows.rhs.data();
  double* const nominal = rows.nominal_rhs.data();
  RowInfo* const info = rows.info.data();
  int r = 0;
  auto add = [&](int contact, const Vec3& a, double d, double support, RowKind kind, int facet) {
    dx[r] = a(0);
    dy[r] = a(1);
    dz[r] = a(2);
    nominal[r] = d;
    rhs[r] = d - confidence * support;
    info[r] = {contact, kind, facet};
    ++r;
  };
  const bool sigmas = normal_sigma != nullptr && confidence > 0.0 && with_friction_facets;
  if (sigmas) {
    normal_sigma->resize(n);
    if (tangential_sigma != nullptr) tangential_sigma->resize(n);
  }
  for (int i = 0; i < n; ++i) {
    rows.contact_first[i] = r;
    const Contact& c = problem.contacts[i];
    const Vec3& nrm = c.normal;
    const Eigen::Matrix3d s =
        confidence > 0.0 ? ellipsoid.ContactCovariance(i) : Eigen::Matrix3d::Zero();
    const Vec3 sn = s * nrm;
    const double snn = nrm.dot(sn);
    if (with_friction_facets) {
      // a = cos t1 + sin t2 - k n with k = mu cos(pi/K); a^T S a expands into
      // six quadratic forms of (t1, t2, n) computed once per contact.
      FacetForms forms;
      std::tie(forms.t1, forms.t2) = TangentBasis(nrm);
      forms.normal = nrm;
      forms.k = c.friction * cos_half;
      const Vec3 s1 = s * forms.t1, s2 = s * forms.t2;
      forms.s11 = forms.t1.dot(s1);
      forms.s22 = forms.t2.dot(s2);
      forms.s12 = forms.t1.dot(s2);
      forms.s1n = forms.t1.dot(sn);
      forms.s2n = forms.t2.dot(sn);
      forms.snn = snn;
      if (sigmas && tangential_sigma)
        (*tangential_sigma)[i] = SpreadOfForms(forms.s11, forms.s12, forms.s22);
      FacetRows(forms, cos_theta, sin_theta, cone_sides, confidence, dx + r, dy + r, dz + r,
                nominal + r, rhs + r);
      for (int j = 0; j < cone_sides; ++j) info[r + j] = {i, RowKind::kFrictionFacet, j};
      r += cone_sides;
    }
    const double normal_support = std::sqrt(std::max(0.0, snn));
    if (sigmas) (*normal_sigma)[i] = normal_support;
    add(i, -nrm, -c.min_normal_force, normal_support, RowKind::kMinNormal, 0);
    if (c.max_normal_force > 0.0) {
      add(i, nrm, c.max_normal_force, normal_support, RowKind::kMaxNormal, 0);
    }
  }
  rows.contact_first[n] = r;
  return sigmas;
}

}  // namespace

void BuildConstraintRows(const PlanProblem& problem, const MeasurementEllipsoid& ellipsoid,
                         int cone_sides, double confidence, bool with_friction_facets,
                         ConstraintRows* out) {
  BuildRows(problem, ellipsoid, cone_sides, confidence, with_friction_facets, out, nullptr,
            nullptr);
}

ConstraintRows BuildConstraintRows(const PlanProblem& problem,
                                   const MeasurementEllipsoid& ellipsoid, int cone_sides,
                                   double confidence, bool with_friction_facets) {
  ConstraintRows rows;
  BuildConstraintRows(problem, ellipsoid, cone_sides, confidence, with_friction_facets, &rows);
  return rows;
}

namespace {

// Calls visit(r, pair) for the slacks of rows r, r + 1 (pair: both lanes)
// and visit_one(r, slack) for a block's odd last row, contact by contact.
// kDotOrder: a_x f_x + (a_y f_y + a_z f_z), else (a_x f_x + a_y f_y) + a_z f_z.
template <bool kDotOrder, typename Pair, typename One>
void ForEachSlack(const ConstraintRows& rows, const double* f, Pair visit, One visit_one) {
  const double* dx = rows.directions.col(0).data();
  const double* dy = rows.directions.col(1).data();
  const double* dz = rows.directions.col(2).data();
  const double* rhs = rows.rhs.data();
  const int n = static_cast<int>(rows.contact_first.size()) - 1;
  for (int i = 0; i < n; ++i) {
    const double fx = f[3 * i], fy = f[3 * i + 1], fz = f[3 * i + 2];
    const __m128d x = _mm_set1_pd(fx), y = _mm_set1_pd(fy), z = _mm_set1_pd(fz);
    int r = rows.contact_first[i];
    const int end = rows.contact_first[i + 1];
    for (; r + 1 < end; r += 2) {
      const __m128d ax = _mm_mul_pd(_mm_loadu_pd(dx + r), x);
      const __m128d ay = _mm_mul_pd(_mm_loadu_pd(dy + r), y);
      const __m128d az = _mm_mul_pd(_mm_loadu_pd(dz + r), z);
      const __m128d dot =
          kDotOrder ? _mm_add_pd(ax, _mm_add_pd(ay, az)) : _mm_add_pd(_mm_add_pd(ax, ay), az);
      visit(r, _mm_sub_pd(_mm_loadu_pd(rhs + r), dot));
    }
    if (r < end) {
      const double dot =
          kDotOrder ? dx[r] * fx + (dy[r] * fy + dz[r] * fz) : dx[r] * fx + dy[r] * fy + dz[r] * fz;
      visit_one(r, rhs[r] - dot);
    }
  }
}

}  // namespace

void RowSlacks(const ConstraintRows& rows, const double* forces, double* slacks) {
  ForEachSlack<false>(
      rows, forces, [slacks](int r, __m128d pair) { _mm_storeu_pd(slacks + r, pair); },
      [slacks](int r, double slack) { slacks[r] = slack; });
}

double MinRowSlack(const ConstraintRows& rows, const double* forces) {
  // Lane minima (a NaN slack, which a finite answer cannot have, is not
  // ordered as std::min would; the least finite value is the same).
  __m128d lanes = _mm_set1_pd(std::numeric_limits<double>::infinity());
  double least = std::numeric_limits<double>::infinity();
  ForEachSlack<true>(
      rows, forces, [&lanes](int, __m128d pair) { lanes = _mm_min_pd(lanes, pair); },
      [&least](int, double slack) { least = std::min(least, slack); });
  return std::min({least, _mm_cvtsd_f64(lanes), _mm_cvtsd_f64(_mm_unpackhi_pd(lanes, lanes))});
}

void RowsOnPlane(const ConstraintRows& rows, const ForceEquilibrium& eq, MatrixXd* plane_matrix,
                 VectorXd* plane_rhs) {
  const int m = static_cast<int>(rows.info.size());
  plane_matrix->resize(m, eq.null_basis.cols());
  *plane_rhs = rows.rhs;
  // A contact's rows are consecutive: one small product per contact.
  const int n = static_cast<int>(rows.contact_first.size()) - 1;
  for (int i = 0; i < n; ++i) {
    const int first = rows.contact_first[i];
    const int count = rows.contact_first[i + 1] - first;
    if (count == 0) continue;
    const auto a = rows.directions.block(first, 0, count, 3);
    plane_matrix->middleRows(first, count).noalias() =
        a.lazyProduct(eq.null_basis.middleRows<3>(3 * i));
    plane_rhs->segment(first, count).noalias() -= a * eq.particular.segment<3>(3 * i);
  }
}

void NormalForceSigma(const PlanProblem& problem, const MeasurementEllipsoid& ellipsoid,
                      std::vector<double>* out) {
  out->resize(problem.contacts.size());
  for (int i = 0; i < static_cast<int>(problem.contacts.size()); ++i) {
    const Vec3& nrm = problem.contacts[i].normal;
    (*out)[i] = std::sqrt(std::max(0.0, nrm.dot(ellipsoid.ContactCovariance(i) * nrm)));
  }
}

std::vector<double> NormalForceSigma(const PlanProblem& problem,
                                     const MeasurementEllipsoid& ellipsoid) {
  std::vector<double> out;
  NormalForceSigma(problem, ellipsoid, &out);
  return out;
}

void TangentialForceSigma(const PlanProblem& problem, const MeasurementEllipsoid& ellipsoid,
                          std::vector<double>* out) {
  out->resize(problem.contacts.size());
  for (int i = 0; i < static_cast<int>(problem.contacts.size()); ++i) {
    (*out)[i] = TangentialSpread(problem.contacts[i].normal, ellipsoid.ContactCovariance(i));
  }
}

double TangentialSpread(const Vec3& normal, const Eigen::Matrix3d& s) {
  // P S P has the normal in its kernel; its other eigenvalues are those of
  // the 2x2 block [t1 t2]^T S [t1 t2].
  const auto [t1, t2] = TangentBasis(normal);
  return SpreadOfForms(t1.dot(s * t1), t1.dot(s * t2), t2.dot(s * t2));
}

std::vector<double> TangentialForceSigma(const PlanProblem& problem,
                                         const MeasurementEllipsoid& ellipsoid) {
  std::vector<double> out;
  TangentialForceSigma(problem, ellipsoid, &out);
  return out;
}

void ExactConeShift(const PlanProblem& problem, const std::vector<double>& normal_sigma,
                    const std::vector<double>& tangential_sigma, double confidence,
                    std::vector<double>* out) {
  out->resize(problem.contacts.size());
  for (size_t i = 0; i < out->size(); ++i) {
    (*out)[i] = confidence * (problem.contacts[i].friction * normal_sigma[i] + tangential_sigma[i]);
  }
}

std::vector<double> ExactConeShift(const PlanProblem& problem,
                                   const std::vector<double>& normal_sigma,
                                   const std::vector<double>& tangential_sigma, double confidence) {
  std::vector<double> out;
  ExactConeShift(problem, normal_sigma, tangential_sigma, confidence, &out);
  return out;
}

double ExactConeSlack(const Vec3& normal, double mu, double shift, const Vec3& force) {
  const Vec3 tangential = force - normal.dot(force) * normal;
  return (mu * normal.dot(force) - shift) - tangential.norm();
}

void PrepareInPlace(const PlanOptions& options, EquilibriumScratch* scratch, PreparedProblem* p,
                    bool geometric_only) {
  ApplyFrictionUncertainty(options.confidence, &p->problem, &p->nominal_friction);
  // The parameter tightening reads G and the independent rows too.
  const bool range_rows = !geometric_only || HasModelUncertainty(p->problem);
  ComputeForceEquilibrium(p->problem, options.rank_tolerance, scratch, &p->equilibrium, range_rows);
  ComputeMeasurementEllipsoid(p->problem, p->equilibrium, &p->ellipsoid);
  // The sigmas come with the rows when those formed the same quadratic forms.
  // The tangential ones serve the EXACT cones only (not a GEOMETRIC solve).
  std::vector<double>* tangential = geometric_only ? nullptr : &p->tangential_sigma;
  if (geometric_only) p->tangential_sigma.clear();
  if (!BuildRows(p->problem, p->ellipsoid, options.cone_sides, options.confidence,
                 options.cone == ConeModel::kPyramid, &p->rows, &p->normal_sigma, tangential)) {
    NormalForceSigma(p->problem, p->ellipsoid, &p->normal_sigma);
    if (tangential != nullptr) TangentialForceSigma(p->problem, p->ellipsoid, tangential);
  }
  if (options.cone == ConeModel::kExact) {
    ExactConeShift(p->problem, p->normal_sigma, p->tangential_sigma, options.confidence,
                   &p->cone_shift);
  } else {
    p->cone_shift.clear();
  }
  TightenForParameters(options, p);
}

PreparedProblem Prepare(PlanProblem validated, const PlanOptions& options) {
  PreparedProblem p;
  p.problem = std::move(validated);
  EquilibriumScratch scratch;
  PrepareInPlace(options, &scratch, &p);
  return p;
}

}  // namespace tactforce::planner
