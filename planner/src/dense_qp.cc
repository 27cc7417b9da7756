// Goldfarb-Idnani dual active-set method (Math. Programming 27, 1983).
//
// Constraints are kept in the form a^T x <= b. The method starts at the
// unconstrained minimum and adds violated constraints one at a time while
// keeping the dual feasible; it maintains J = L^-T Q and the upper
// triangular R of the QR factorisation of L^-1 N_active (H = L L^T), updated
// by Givens rotations when a constraint enters or leaves, so each step costs
// O(n^2). With H = I (identity_hessian) there is nothing to factorise: J
// starts as I. Every buffer lives in the caller's DenseQpWorkspace.
#include "tactforce/planner/dense_qp.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

#ifdef __SSE2__
#include <emmintrin.h>
#endif

#include <Eigen/Cholesky>

namespace tactforce::planner {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kInf = std::numeric_limits<double>::infinity();
// Rows with a normal shorter than this are treated as 0^T x <= b.
constexpr double kZeroNorm = 1e-200;

// a . b over n entries, two lanes at a time (the pairs' sums added last).
inline double Dot(int n, const double* __restrict a, const double* __restrict b) {
  int i = 0;
  double sum = 0.0;
#ifdef __SSE2__
  __m128d acc = _mm_setzero_pd();
  for (; i + 1 < n; i += 2)
    acc = _mm_add_pd(acc, _mm_mul_pd(_mm_loadu_pd(a + i), _mm_loadu_pd(b + i)));
  sum = _mm_cvtsd_f64(acc) + _mm_cvtsd_f64(_mm_unpackhi_pd(acc, acc));
#endif
  for (; i < n; ++i) sum += a[i] * b[i];
  return sum;
}

// y += alpha x over n entries (vectorised: the pointers do not alias).
inline void Axpy(int n, double alpha, const double* __restrict x, double* __restrict y) {
  for (int i = 0; i < n; ++i) y[i] += alpha * x[i];
}

// [x y] <- [x y] [c -s; s c] over n entries: the columns' part of a Givens
// rotation (vectorised: the pointers do not alias).
inline void Rotate(int n, double c, double s, double* __restrict x, double* __restrict y) {
  for (int i = 0; i < n; ++i) {
    const double a = x[i], b = y[i];
    x[i] = c * a + s * b;
    y[i] = -s * a + c * b;
  }
}

// Rotation (c, s) with [c s; -s c] [a; b] = [h; 0]. sqrt(a^2 + b^2) unless
// that would over- or underflow (std::hypot costs several times more).
void Givens(double a, double b, double* c, double* s, double* h) {
  const double h2 = a * a + b * b;
  *h = (h2 > 1e-290 && h2 < 1e290) ? std::sqrt(h2) : std::hypot(a, b);
  if (*h == 0.0) {
    *c = 1.0;
    *s = 0.0;
  } else {
    *c = a / *h;
    *s = b / *h;
  }
}

// The row structure applies when `in_matrix` has no rows and the structure
// describes exactly the rows of `in_rhs` (a workspace's DenseQp reused by a
// caller that fills `in_matrix` keeps stale structure, which is then ignored).
// distance[r] = b'_r - a'_r . y for `count` unit rows (the 4 columns of
// `unit`, `stride` apart: a'_x, a'_y, a'_z, b'), and their least value: the
// innermost loop of the solver, two rows per SSE2 instruction, inlined into
// the block scan (a call per block cost more than the pair loop saved).
inline __attribute__((always_inline)) double UnitRowDistances(const double* __restrict unit,
                                                              int stride, int count, double y0,
                                                              double y1, double y2,
                                                              double* __restrict distance) {
  const double* ux = unit;
  const double* uy = unit + stride;
  const double* uz = unit + 2 * stride;
  const double* ub = unit + 3 * stride;
  double least = kInf;
  int r = 0;
#ifdef __SSE2__
  const __m128d vy0 = _mm_set1_pd(y0), vy1 = _mm_set1_pd(y1), vy2 = _mm_set1_pd(y2);
  __m128d vleast = _mm_set1_pd(kInf);
  for (; r + 1 < count; r += 2) {
    const __m128d dot = _mm_add_pd(
        _mm_add_pd(_mm_mul_pd(_mm_loadu_pd(ux + r), vy0), _mm_mul_pd(_mm_loadu_pd(uy + r), vy1)),
        _mm_mul_pd(_mm_loadu_pd(uz + r), vy2));
    const __m128d d = _mm_sub_pd(_mm_loadu_pd(ub + r), dot);
    _mm_storeu_pd(distance + r, d);
    vleast = _mm_min_pd(vleast, d);
  }
  least = std::min(_mm_cvtsd_f64(vleast), _mm_cvtsd_f64(_mm_unpackhi_pd(vleast, vleast)));
#endif
  for (; r < count; ++r) {
    distance[r] = ub[r] - (ux[r] * y0 + uy[r] * y1 + uz[r] * y2);
    least = std::min(least, distance[r]);
  }
  return least;
}

bool UsesRowStructure(const DenseQp& qp) {
  const Eigen::Index m = qp.in_rhs.size();
  const std::vector<int>& first = qp.in_block_first;
  if (qp.in_matrix.rows() != 0 || m == 0 || qp.in_directions.rows() != m || first.size() < 2 ||
      qp.in_block_maps.cols() != qp.gradient.size() ||
      qp.in_block_maps.rows() != 3 * static_cast<Eigen::Index>(first.size() - 1) ||
      first.front() != 0 || first.back() != m) {
    return false;
  }
  return std::is_sorted(first.begin(), first.end());
}

// The iterate and the factorisation of one solve. Up to MaxN variables they
// live in fixed-capacity storage on the stack, whose small products Eigen
// evaluates inline; beyond that, in the DenseQpWorkspace (WorkspaceFactors).
template <int MaxN>
struct SmallFactors {
  static constexpr int kN = 0;  // the size is known at run time only
  using Matrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, 0, MaxN, MaxN>;
  using Vector = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, MaxN, 1>;
  Matrix J, R;  // n x n
  Vector x, d, z, r, u, hx;
};

// Exactly N variables (the FE-plane sizes 1..12 of 2..6 contacts): every
// loop over the variables has a compile-time trip count, so the compiler
// unrolls and vectorises the O(n^2) updates.
template <int N>
struct FixedFactors {
  static constexpr int kN = N;
  Eigen::Matrix<double, N, N> J, R;
  Eigen::Matrix<double, N, 1> x, d, z, r, u, hx;
};

struct WorkspaceFactors {
  static constexpr int kN = 0;
  explicit WorkspaceFactors(DenseQpWorkspace& w)
      : J(w.J), R(w.R), x(w.x), d(w.d), z(w.z), r(w.r), u(w.u), hx(w.hx) {}
  MatrixXd &J, &R;
  VectorXd &x, &d, &z, &r, &u, &hx;
};

// One solve: constraint data in the DenseQpWorkspace, iterate and factors in
// `Factors`. The active set has at most n constraints; r and u use their
// leading q = active.size() entries.
template <class Factors>
class ActiveSetSolver {
 public:
  ActiveSetSolver(const DenseQp& qp, const DenseQpSettings& settings, DenseQpWorkspace* ws,
                  Factors* factors)
      : qp_(qp),
        settings_(settings),
        w_(*ws),
        f_(*factors),
        n_(static_cast<int>(qp.gradient.size())),
        p_(static_cast<int>(qp.eq_matrix.rows())),
        structured_(UsesRowStructure(qp)),
        m_(static_cast<int>(structured_ ? qp.in_directions.rows() : qp.in_matrix.rows())) {}

  void Run(DenseQpResult* out);

 private:
  // Constraint k of the stacked set (equalities first, then inequalities),
  // as a contiguous column of the normals (after EnsureNormal(k)).
  auto Normal(int k) const { return w_.normals.col(k); }
  // Forms the normal of constraint k and its norm, once per solve.
  void EnsureNormal(int k);
  // The norms of every row, and from them 1 / |a|, the distance bounds and
  // (structured) the unit rows; the first row 0^T x <= b with b < 0 in
  // impossible_row_.
  void StructuredRowScales();
  void DenseRowScales();
  // The Gram matrix M_b M_b^T of every block, 6 entries each, into `gram`.
  void BlockGrams(double* gram) const;
  // Row i's norm and inverse norm (0 for a zero row, which may be
  // impossible_row_); dense rows: also its distance bound.
  void NormOfRow(int i, double norm);
  // The distance bounds and unit rows of all structured rows.
  void UnitRows();

  // The bound of inequality row i while it is inactive (RowScales()).
  double DistanceBound(int i) const {
    return -settings_.tolerance * std::max(1.0, std::abs(qp_.in_rhs(i))) * w_.inverse_norms(i);
  }
  // distance = (b - A x) / |a| of every inequality row (dense rows), into
  // w_.distance.
  void ScanRows();
  // The same for structured rows, block by block; each block's farthest
  // row violated beyond `threshold` (SelectInRange) goes to w_.pending.
  void ScanBlocks(double threshold);
  // Adds a violated row to w_.pending, in the order of its distance.
  void Push(int row);
  // Rows [begin, end) of w_.distance, whose least entry is `least`: the
  // inactive row farthest outside its half-space, if it is violated and
  // farther than *worst_distance.
  void SelectInRange(int begin, int end, double least, double* worst_distance, int* worst) const;

  double Slack(int k) const { return w_.rhs(k) - w_.normals.col(k).dot(f_.x); }
  double Scale(int k) const {
    return std::max({1.0, std::abs(w_.rhs(k)), w_.normal_norms(k) * f_.x.norm()});
  }
  int Active() const { return static_cast<int>(w_.active.size()); }
  // |z| > tolerance max(1, |a_k|): constraint k is not (numerically) a
  // combination of the active ones. Squared, without a square root.
  bool DirectionIsLong(int k) const {
    const double length = settings_.tolerance * std::max(1.0, w_.normal_norms(k));
    return f_.z.squaredNorm() > length * length;
  }
  // Normals, right-hand sides, J = L^-T and the unconstrained minimum;
  // false if H is not positive definite.
  bool Initialize();
  // Makes every equality active; returns the first inconsistent one, or -1.
  int AddEqualities();
  // Adds inequality k (stacked index), dropping blocking constraints on the
  // way; nullopt once added, else why the solve ends.
  std::optional<DenseQpStatus> AddInequality(int k, int max_iterations);
  // Active inequality limiting the partial step (its position in active, or
  // -1) and that step length (infinite if none).
  int BlockingActive(double* step) const;
  // Direction in primal (z) and dual (r) spaces for adding constraint k.
  void Directions(int k);
  // The same after DropFromFactorization, from the d it turned.
  void DirectionsAfterDrop();
  // r = R^-1 d_1.
  void BackSubstitute();
  void AddToFactorization();
  void AddByRotations();
  void DropFromFactorization(int position);
  // Appends stacked constraint k to the active set with multiplier `u`.
  void Activate(int k, double u);
  int MostViolated();
  void Finish(DenseQpStatus status, int blocking, DenseQpResult* out);

  const DenseQp& qp_;
  const DenseQpSettings& settings_;
  DenseQpWorkspace& w_;
  Factors& f_;
  // The number of variables, a compile-time constant for FixedFactors.
  int N() const {
    if constexpr (Factors::kN > 0) {
      return Factors::kN;
    } else {
      return n_;
    }
  }
  const int n_, p_;
  const bool structured_;
  const int m_;
  int iterations_ = 0;
  int active_equalities_ = 0;  // the leading entries of w_.active
  int pending_count_ = 0;      // the leading entries of w_.pending in use
  int impossible_row_ = -1;    // a row 0^T x <= b with b < 0 (the row scales), or -1
};

// Plain loops over contiguous columns: for the few variables of these QPs a
// general matrix-vector kernel costs more in set-up than in arithmetic.
template <class Factors>
void ActiveSetSolver<Factors>::Directions(int k) {
  const int q = Active();
  const double* a = w_.normals.col(k).data();
  // d = J^T a
  for (int i = 0; i < N(); ++i) f_.d(i) = Dot(N(), f_.J.col(i).data(), a);
  // z = J_2 d_2 (the columns after the active ones)
  double* z = f_.z.data();
  std::fill(z, z + N(), 0.0);
  for (int c = q; c < N(); ++c) Axpy(N(), f_.d(c), f_.J.col(c).data(), z);
  BackSubstitute();
}

template <class Factors>
void ActiveSetSolver<Factors>::DirectionsAfterDrop() {
  // The drop turned J's columns and d alike and freed column q: J_2 gained
  // it, so z gains its term; only r is formed again.
  const int q = Active();
  Axpy(N(), f_.d(q), f_.J.col(q).data(), f_.z.data());
  BackSubstitute();
}

template <class Factors>
void ActiveSetSolver<Factors>::BackSubstitute() {
  // r = R^-1 d_1 (R upper triangular, q x q), by columns (contiguous), in
  // place on a copy of d_1.
  const int q = Active();
  double* r = f_.r.data();
  for (int i = 0; i < q; ++i) r[i] = f_.d(i);
  for (int c = q - 1; c >= 0; --c) {
    r[c] /= f_.R(c, c);
    Axpy(c, -r[c], f_.R.col(c).data(), r);
  }
}

template <class Factors>
void ActiveSetSolver<Factors>::AddToFactorization() {
  // J_2 (the columns after the active ones) is turned so that d_2 = J_2^T a
  // becomes |d_2| e_1 by one Householder reflection I - 2 v v^T / v^T v,
  // v = d_2 - alpha e_1: a rank-1 update J_2 -= w v^T with w = J_2 v 2 / v^T v
  // and J_2 v = z - alpha J_q (z = J_2 d_2 from Directions), a quarter of the
  // arithmetic of a chain of Givens rotations. The new column q is then
  // z / |d_2| (the reflection's z / alpha, its sign turned so that R keeps a
  // positive diagonal).
  const int q = Active();  // before adding
  auto& d = f_.d;
  auto& J = f_.J;
  double tail = 0.0;  // |d_2|^2
  for (int j = q; j < N(); ++j) tail += d(j) * d(j);
  if (!(tail > 1e-290 && tail < 1e290)) return AddByRotations();
  const double norm = std::sqrt(tail);
  const double alpha = d(q) > 0.0 ? -norm : norm;
  const double scale = 1.0 / (norm * (norm + std::abs(d(q))));  // 2 / v^T v
  double* __restrict wv = f_.hx.data();                         // w; hx is free until Finish
  const double* z = f_.z.data();
  const double* column_q = J.col(q).data();
  for (int row = 0; row < N(); ++row) wv[row] = (z[row] - alpha * column_q[row]) * scale;
  for (int c = q + 1; c < N(); ++c) Axpy(N(), -d(c), wv, J.col(c).data());
  const double inverse = 1.0 / norm;
  double* new_column = J.col(q).data();
  for (int row = 0; row < N(); ++row) new_column[row] = z[row] * inverse;
  f_.R.col(q).head(q) = d.head(q);
  f_.R(q, q) = norm;
}

template <class Factors>
void ActiveSetSolver<Factors>::AddByRotations() {
  // The same by Givens rotations (d_2 too long or too short to square).
  const int q = Active();
  auto& d = f_.d;
  auto& J = f_.J;
  for (int j = N() - 1; j > q; --j) {
    double c, s, h;
    Givens(d(j - 1), d(j), &c, &s, &h);
    if (s == 0.0) continue;
    d(j - 1) = h;
    d(j) = 0.0;
    Rotate(N(), c, s, J.col(j - 1).data(), J.col(j).data());
  }
  f_.R.col(q).head(q + 1) = d.head(q + 1);
}

template <class Factors>
void ActiveSetSolver<Factors>::Activate(int k, double u) {
  f_.u(Active()) = u;
  w_.active.push_back(k);
  w_.is_active[k] = 1;
  if (k >= p_) w_.distance_bound(k - p_) = -kInf;
}

template <class Factors>
void ActiveSetSolver<Factors>::DropFromFactorization(int position) {
  const int q = Active();  // before removal
  auto& R = f_.R;
  auto& J = f_.J;
  const int leaving = w_.active[position];
  w_.is_active[leaving] = 0;
  if (leaving >= p_) w_.distance_bound(leaving - p_) = DistanceBound(leaving - p_);
  for (int col = position; col < q - 1; ++col) R.col(col) = R.col(col + 1);
  R.col(q - 1).setZero();
  for (int j = position; j < q - 1; ++j) {
    double c, s, h;
    Givens(R(j, j), R(j + 1, j), &c, &s, &h);
    if (s == 0.0) continue;
    for (int col = j; col < q - 1; ++col) {
      const double a = R(j, col), b = R(j + 1, col);
      R(j, col) = c * a + s * b;
      R(j + 1, col) = -s * a + c * b;
    }
    Rotate(N(), c, s, J.col(j).data(), J.col(j + 1).data());
    // d = J^T a of the constraint being added turns with J.
    const double a = f_.d(j), b = f_.d(j + 1);
    f_.d(j) = c * a + s * b;
    f_.d(j + 1) = -s * a + c * b;
  }
  w_.active.erase(w_.active.begin() + position);
  for (int k = position; k < q - 1; ++k) f_.u(k) = f_.u(k + 1);
}

template <class Factors>
void ActiveSetSolver<Factors>::EnsureNormal(int k) {
  if (w_.has_normal[k]) return;
  double* normal = w_.normals.col(k).data();
  if (k < p_) {
    for (int j = 0; j < N(); ++j) normal[j] = qp_.eq_matrix(k, j);
  } else if (structured_) {  // its norm is already known (StructuredRowScales)
    const int row = k - p_;
    const int* first = qp_.in_block_first.data();
    int block = 0;  // a few blocks: a linear search
    while (first[block + 1] <= row) ++block;
    const double a0 = qp_.in_directions(row, 0), a1 = qp_.in_directions(row, 1),
                 a2 = qp_.in_directions(row, 2);
    for (int j = 0; j < N(); ++j) {
      const double* map = qp_.in_block_maps.col(j).data() + 3 * block;
      normal[j] = a0 * map[0] + a1 * map[1] + a2 * map[2];
    }
    w_.has_normal[k] = 1;
    return;
  } else {  // its norm is already known (DenseRowScales)
    for (int j = 0; j < N(); ++j) normal[j] = qp_.in_matrix(k - p_, j);
    w_.has_normal[k] = 1;
    return;
  }
  w_.normal_norms(k) = w_.normals.col(k).norm();
  w_.has_normal[k] = 1;
}

template <class Factors>
void ActiveSetSolver<Factors>::BlockGrams(double* gram) const {
  // Entries 0..5 of block b: (M M^T)_00, _01, _02, _11, _12, _22, each
  // summed over the variables in order; two entries per SSE2 instruction.
  const int values = static_cast<int>(qp_.in_block_maps.rows());
  for (int b = 0; b < values / 3; ++b) {
    const double* map = qp_.in_block_maps.data() + 3 * b;
    double* g = gram + 6 * b;
#ifdef __SSE2__
    __m128d g01 = _mm_setzero_pd(), g23 = _mm_setzero_pd(), g45 = _mm_setzero_pd();
    for (int j = 0; j < N(); ++j) {
      const double* c = map + j * values;
      const __m128d c01 = _mm_loadu_pd(c), c12 = _mm_loadu_pd(c + 1);
      g01 = _mm_add_pd(g01, _mm_mul_pd(_mm_set1_pd(c[0]), c01));
      g23 = _mm_add_pd(g23, _mm_mul_pd(c01, _mm_shuffle_pd(c12, c12, 1)));
      g45 = _mm_add_pd(g45, _mm_mul_pd(_mm_set1_pd(c[2]), c12));
    }
    _mm_storeu_pd(g, g01);
    _mm_storeu_pd(g + 2, g23);
    _mm_storeu_pd(g + 4, g45);
#else
    std::fill(g, g + 6, 0.0);
    for (int j = 0; j < N(); ++j) {
      const double* c = map + j * values;
      g[0] += c[0] * c[0];
      g[1] += c[0] * c[1];
      g[2] += c[0] * c[2];
      g[3] += c[1] * c[1];
      g[4] += c[1] * c[2];
      g[5] += c[2] * c[2];
    }
#endif
  }
}

template <class Factors>
void ActiveSetSolver<Factors>::NormOfRow(int i, double norm) {
  // A zero row (0 <= b) gets inverse norm 0: distance 0 and bound -0, so it
  // is never selected; Run reports it first when b < 0.
  const double b = qp_.in_rhs(i), tol = settings_.tolerance;
  const double size = std::max(1.0, std::abs(b));
  w_.normal_norms(p_ + i) = norm;
  if (norm > kZeroNorm) {
    w_.inverse_norms(i) = 1.0 / norm;
  } else {
    w_.inverse_norms(i) = 0.0;
    if (impossible_row_ < 0 && b < -tol * size) impossible_row_ = p_ + i;
  }
  if (!structured_) w_.distance_bound(i) = -tol * size * w_.inverse_norms(i);
}

template <class Factors>
void ActiveSetSolver<Factors>::StructuredRowScales() {
  // |M_b^T a|^2 = a^T (M_b M_b^T) a from one 3x3 Gram matrix per block; then
  // 1 / |a|, the distance bound and the unit row (a / |a|, b / |a|), two
  // rows per SSE2 instruction, in one pass.
  const int blocks = static_cast<int>(qp_.in_block_maps.rows()) / 3;
  if (w_.block_values.size() < 6 * blocks) w_.block_values.resize(6 * blocks);
  const double* g_all = w_.block_values.data();
  BlockGrams(w_.block_values.data());
  const double* __restrict ax = qp_.in_directions.col(0).data();
  const double* __restrict ay = qp_.in_directions.col(1).data();
  const double* __restrict az = qp_.in_directions.col(2).data();
  double* __restrict norms = w_.normal_norms.data() + p_;
  double* __restrict inverses = w_.inverse_norms.data();
  impossible_row_ = -1;
  // Two passes, so that each keeps its values in registers: the norms per
  // block (its Gram matrix), then the scales of all rows from 1 / |a|.
  for (int b = 0; b < blocks; ++b) {
    const double* g = g_all + 6 * b;
    const double g0 = g[0], g1 = 2.0 * g[1], g2 = 2.0 * g[2], g3 = g[3], g4 = 2.0 * g[4], g5 = g[5];
    const int end = qp_.in_block_first[b + 1];
    int i = qp_.in_block_first[b];
#ifdef __SSE2__
    const __m128d G0 = _mm_set1_pd(g0), G1 = _mm_set1_pd(g1), G2 = _mm_set1_pd(g2);
    const __m128d G3 = _mm_set1_pd(g3), G4 = _mm_set1_pd(g4), G5 = _mm_set1_pd(g5);
    const __m128d one = _mm_set1_pd(1.0), tiny = _mm_set1_pd(kZeroNorm);
    for (; i + 1 < end; i += 2) {
      const __m128d X = _mm_loadu_pd(ax + i), Y = _mm_loadu_pd(ay + i), Z = _mm_loadu_pd(az + i);
      const __m128d xpart = _mm_mul_pd(
          X, _mm_add_pd(_mm_add_pd(_mm_mul_pd(G0, X), _mm_mul_pd(G1, Y)), _mm_mul_pd(G2, Z)));
      const __m128d ypart = _mm_mul_pd(Y, _mm_add_pd(_mm_mul_pd(G3, Y), _mm_mul_pd(G4, Z)));
      const __m128d squared =
          _mm_add_pd(_mm_add_pd(xpart, ypart), _mm_mul_pd(_mm_mul_pd(G5, Z), Z));
      const __m128d norm = _mm_sqrt_pd(_mm_max_pd(squared, _mm_setzero_pd()));
      const __m128d nonzero = _mm_cmpgt_pd(norm, tiny);
      _mm_storeu_pd(norms + i, norm);
      _mm_storeu_pd(inverses + i, _mm_and_pd(nonzero, _mm_div_pd(one, norm)));
      if (_mm_movemask_pd(nonzero) != 3 && impossible_row_ < 0) {  // a zero row
        for (int row = i; row < i + 2; ++row) {
          const double b = qp_.in_rhs(row);
          if (!(norms[row] > kZeroNorm) && b < -settings_.tolerance * std::max(1.0, std::abs(b))) {
            impossible_row_ = p_ + row;
            break;
          }
        }
      }
    }
#endif
    for (; i < end; ++i) {
      const double squared = ax[i] * (g0 * ax[i] + g1 * ay[i] + g2 * az[i]) +
                             ay[i] * (g3 * ay[i] + g4 * az[i]) + g5 * az[i] * az[i];
      NormOfRow(i, std::sqrt(std::max(0.0, squared)));
    }
  }
  UnitRows();
}

template <class Factors>
void ActiveSetSolver<Factors>::UnitRows() {
  // The distance bounds -tolerance max(1, |b|) / |a| and the unit rows
  // (a / |a|, b / |a|) of all rows, two per SSE2 instruction; zero rows
  // (inverse norm 0) get bound -0 and zeros.
  const double* __restrict ax = qp_.in_directions.col(0).data();
  const double* __restrict ay = qp_.in_directions.col(1).data();
  const double* __restrict az = qp_.in_directions.col(2).data();
  const double* __restrict rhs = qp_.in_rhs.data();
  const double* __restrict inverses = w_.inverse_norms.data();
  double* __restrict bounds = w_.distance_bound.data();
  const int stride = static_cast<int>(w_.unit_rows.rows());
  double* __restrict ux = w_.unit_rows.data();
  double* __restrict uy = ux + stride;
  double* __restrict uz = uy + stride;
  double* __restrict ub = uz + stride;
  const double minus_tol = -settings_.tolerance;
  int i = 0;
#ifdef __SSE2__
  const __m128d one = _mm_set1_pd(1.0), sign = _mm_set1_pd(-0.0), vtol = _mm_set1_pd(minus_tol);
  for (; i + 1 < m_; i += 2) {
    const __m128d inverse = _mm_loadu_pd(inverses + i), B = _mm_loadu_pd(rhs + i);
    const __m128d size = _mm_max_pd(_mm_andnot_pd(sign, B), one);
    _mm_storeu_pd(bounds + i, _mm_mul_pd(_mm_mul_pd(vtol, size), inverse));
    _mm_storeu_pd(ux + i, _mm_mul_pd(_mm_loadu_pd(ax + i), inverse));
    _mm_storeu_pd(uy + i, _mm_mul_pd(_mm_loadu_pd(ay + i), inverse));
    _mm_storeu_pd(uz + i, _mm_mul_pd(_mm_loadu_pd(az + i), inverse));
    _mm_storeu_pd(ub + i, _mm_mul_pd(B, inverse));
  }
#endif
  for (; i < m_; ++i) {
    const double inverse = inverses[i];
    bounds[i] = minus_tol * std::max(1.0, std::abs(rhs[i])) * inverse;
    ux[i] = ax[i] * inverse;
    uy[i] = ay[i] * inverse;
    uz[i] = az[i] * inverse;
    ub[i] = rhs[i] * inverse;
  }
}

template <class Factors>
void ActiveSetSolver<Factors>::DenseRowScales() {
  double* __restrict norms = w_.normal_norms.data() + p_;
  std::fill(norms, norms + m_, 0.0);
  for (int j = 0; j < N(); ++j) {
    const double* __restrict column = qp_.in_matrix.col(j).data();
    for (int i = 0; i < m_; ++i) norms[i] += column[i] * column[i];
  }
  impossible_row_ = -1;
  const double* b = qp_.in_rhs.data();
  const double tol = settings_.tolerance;
  for (int i = 0; i < m_; ++i) {
    const double norm = std::sqrt(norms[i]);
    if (norm > kZeroNorm) {
      const double inverse = 1.0 / norm;
      norms[i] = norm;
      w_.inverse_norms(i) = inverse;
      w_.distance_bound(i) = -tol * std::max(1.0, std::abs(b[i])) * inverse;
    } else {
      NormOfRow(i, norm);
    }
  }
}

template <class Factors>
void ActiveSetSolver<Factors>::ScanRows() {
  double* __restrict distance = w_.distance.data();
  const double* __restrict b = qp_.in_rhs.data();
  const double* __restrict inverse = w_.inverse_norms.data();
  // slack = b - A x, column by column (A is m x n, column-major)
  std::copy(b, b + m_, distance);
  for (int j = 0; j < N(); ++j) {
    const double xj = f_.x(j);
    const double* __restrict column = qp_.in_matrix.col(j).data();
    for (int i = 0; i < m_; ++i) distance[i] -= xj * column[i];
  }
  for (int i = 0; i < m_; ++i) distance[i] *= inverse[i];
}

template <class Factors>
void ActiveSetSolver<Factors>::SelectInRange(int begin, int end, double least,
                                             double* worst_distance, int* worst) const {
  // Violated: slack < -tolerance max(1, |b|, |a| |x|), i.e. a distance below
  // both the row's bound and -tolerance |x| (*worst_distance starts there;
  // active rows have bound -inf). The farthest violated row enters (DAQP's
  // rule on normalised rows), which takes fewer steps here than the largest
  // relative violation. Rows are visited one by one only when the range's
  // least distance beats *worst_distance.
  if (!(least < *worst_distance)) return;
  const double* distance = w_.distance.data();
  const double* bound = w_.distance_bound.data();
  for (int i = begin; i < end; ++i) {
    if (distance[i] == least) {
      if (least < bound[i]) {  // the usual case: the farthest row is violated
        *worst_distance = least;
        *worst = i;
        return;
      }
      break;
    }
  }
  for (int i = begin; i < end; ++i) {  // it is active or within tolerance
    const double d = distance[i];
    if (d < bound[i] && d < *worst_distance) {
      *worst_distance = d;
      *worst = i;
    }
  }
}

template <class Factors>
void ActiveSetSolver<Factors>::ScanBlocks(double threshold) {
  // Per block: y = M_b x (3 N products, unrolled for FixedFactors), then 3
  // products per unit row. No block is skipped: a bound such as
  // |a_r| |y_b - y_ref| proving its rows satisfied costs more than it saves,
  // since on the planner's grasps nearly every block holds an active or
  // nearly active row. Each block's farthest violated row is kept in
  // w_.pending (Push).
  const int values = static_cast<int>(qp_.in_block_maps.rows());
  const auto& unit = w_.unit_rows;
  const double* __restrict x = f_.x.data();
  const int blocks = values / 3;
  for (int block = 0; block < blocks; ++block) {
    const double* __restrict map = qp_.in_block_maps.data() + 3 * block;
    double y0 = 0.0, y1 = 0.0, y2 = 0.0;
#ifdef __SSE2__
    __m128d y01 = _mm_setzero_pd();
    for (int j = 0; j < N(); ++j) {
      const double* column = map + j * values;
      y01 = _mm_add_pd(y01, _mm_mul_pd(_mm_set1_pd(x[j]), _mm_loadu_pd(column)));
      y2 += x[j] * column[2];
    }
    y0 = _mm_cvtsd_f64(y01);
    y1 = _mm_cvtsd_f64(_mm_unpackhi_pd(y01, y01));
#else
    for (int j = 0; j < N(); ++j) {
      const double* column = map + j * values;
      y0 += x[j] * column[0];
      y1 += x[j] * column[1];
      y2 += x[j] * column[2];
    }
#endif
    const int first = qp_.in_block_first[block], end = qp_.in_block_first[block + 1];
    const double least = UnitRowDistances(unit.data() + first, static_cast<int>(unit.rows()),
                                          end - first, y0, y1, y2, w_.distance.data() + first);
    double block_distance = threshold;
    int block_row = -1;
    SelectInRange(first, end, least, &block_distance, &block_row);
    if (block_row >= 0) Push(block_row);
  }
}

template <class Factors>
void ActiveSetSolver<Factors>::Push(int row) {
  // Kept most violated last (popped first): a few entries, insertion sort.
  int* pending = w_.pending.data();  // sized to the blocks (Initialize)
  const double* distance = w_.distance.data();
  pending[pending_count_] = row;
  for (int i = pending_count_++; i > 0 && distance[pending[i - 1]] < distance[pending[i]]; --i) {
    std::swap(pending[i - 1], pending[i]);
  }
}

template <class Factors>
int ActiveSetSolver<Factors>::MostViolated() {
  // Relative violation: slack / max(1, |b|, |a| |x|).
  const double x_norm = f_.x.norm();
  const double tol = settings_.tolerance;
  auto violation = [&](int k, double slack) {
    return slack / std::max({1.0, std::abs(w_.rhs(k)), w_.normal_norms(k) * x_norm});
  };
  for (int row : settings_.warm_start) {
    const int k = p_ + row;
    if (row < 0 || row >= m_ || w_.is_active[k]) continue;
    EnsureNormal(k);
    if (violation(k, Slack(k)) < -tol) return k;
  }
  if (m_ == 0) return -1;
  double worst_distance = -tol * x_norm;
  int worst = -1;
  if (structured_) {
    // The other blocks' violated rows of the last scan are tried before a
    // new scan, in the order of their distance then, each if it is still at
    // least half as far outside as it was (w_.distance keeps the scan's
    // values): one scan then serves several steps. Taking every row still
    // violated costs more steps (drops) than the scans it saves at 3-4
    // contacts; only the first scan's rows, more still.
    while (pending_count_ > 0) {
      const int row = w_.pending[--pending_count_];
      const int k = p_ + row;
      if (w_.is_active[k]) continue;
      EnsureNormal(k);
      const double distance = Slack(k) * w_.inverse_norms(row);
      if (distance < w_.distance_bound(row) && distance < worst_distance &&
          distance <= 0.5 * w_.distance(row)) {
        return k;
      }
    }
    ScanBlocks(worst_distance);
    if (pending_count_ == 0) return -1;
    worst = w_.pending[--pending_count_];
  } else {
    ScanRows();
    const double least =
        m_ > 0 ? *std::min_element(w_.distance.data(), w_.distance.data() + m_) : kInf;
    SelectInRange(0, m_, least, &worst_distance, &worst);
  }
  return worst < 0 ? -1 : p_ + worst;
}

template <class Factors>
void ActiveSetSolver<Factors>::Finish(DenseQpStatus status, int blocking, DenseQpResult* out) {
  out->status = status;
  out->x = f_.x;
  if (qp_.identity_hessian) {
    out->objective = 0.5 * f_.x.squaredNorm() + qp_.gradient.dot(f_.x);
  } else {
    f_.hx.noalias() = qp_.hessian * f_.x;
    out->objective = 0.5 * f_.x.dot(f_.hx) + qp_.gradient.dot(f_.x);
  }
  out->in_multipliers.setZero(m_);
  out->eq_multipliers.setZero(p_);
  out->active_set.clear();
  for (int i = 0; i < Active(); ++i) {
    const int k = w_.active[i];
    if (k < p_) {
      out->eq_multipliers(k) = f_.u(i);
    } else {
      out->in_multipliers(k - p_) = f_.u(i);
      out->active_set.push_back(k - p_);
    }
  }
  out->iterations = iterations_;
  out->blocking_row = blocking < 0 ? -1 : (blocking < p_ ? -1 - blocking : blocking - p_);
}

template <class Factors>
bool ActiveSetSolver<Factors>::Initialize() {
  w_.is_active.assign(p_ + m_, 0);
  w_.has_normal.assign(p_ + m_, 0);
  w_.active.clear();
  w_.active.reserve(N() + 1);
  pending_count_ = 0;
  if (structured_ && w_.pending.size() < qp_.in_block_first.size()) {
    w_.pending.resize(qp_.in_block_first.size());  // at most one row per block
  }
  // Buffers only grow, so grasps of varying row counts reuse them.
  if (w_.normals.rows() != N() || w_.normals.cols() < p_ + m_) w_.normals.resize(N(), p_ + m_);
  if (structured_ && w_.unit_rows.rows() < m_) w_.unit_rows.resize(m_, 4);
  for (VectorXd* v : {&w_.rhs, &w_.normal_norms}) {
    if (v->size() < p_ + m_) v->resize(p_ + m_);
  }
  for (VectorXd* v : {&w_.distance, &w_.distance_bound, &w_.inverse_norms}) {
    if (v->size() < m_) v->resize(m_);
  }
  w_.rhs.head(p_) = qp_.eq_rhs;
  w_.rhs.segment(p_, m_) = qp_.in_rhs;
  if (structured_) {
    StructuredRowScales();
  } else {
    DenseRowScales();
  }
  f_.x.resize(N());
  f_.d.resize(N());
  f_.z.resize(N());
  f_.r.resize(N());
  f_.u.resize(N());
  f_.hx.resize(N());
  f_.R.setZero(N(), N());
  if (qp_.identity_hessian) {  // L = I: J = I, x = -g
    f_.J.setIdentity(N(), N());
    f_.x = -qp_.gradient;
    return true;
  }
  w_.llt.compute(qp_.hessian);
  if (w_.llt.info() != Eigen::Success) {
    f_.x.setZero();
    return false;
  }
  // J = L^-T; unconstrained minimum x = -H^-1 g.
  f_.J.setIdentity(N(), N());
  w_.llt.matrixU().solveInPlace(f_.J);
  f_.x = -qp_.gradient;
  w_.llt.solveInPlace(f_.x);
  return true;
}

template <class Factors>
int ActiveSetSolver<Factors>::AddEqualities() {
  const double tol = settings_.tolerance;
  for (int k = 0; k < p_; ++k) {
    EnsureNormal(k);
    Directions(k);
    const double zn = f_.z.dot(Normal(k));
    if (!DirectionIsLong(k) || std::abs(zn) <= tol) {
      // Dependent on earlier equalities: redundant if already satisfied.
      if (std::abs(Slack(k)) <= 1e3 * tol * Scale(k)) continue;
      return k;
    }
    const double t = -Slack(k) / zn;  // moves x onto the hyperplane
    const int q = Active();
    f_.x -= t * f_.z;
    if (q > 0) f_.u.head(q) -= t * f_.r.head(q);
    AddToFactorization();
    Activate(k, t);
    ++active_equalities_;
  }
  return -1;
}

template <class Factors>
int ActiveSetSolver<Factors>::BlockingActive(double* step) const {
  // Along the step x -= t z the multipliers move as u -= t r.
  *step = kInf;
  int drop = -1;
  // The active equalities come first (never dropped) and are skipped.
  for (int i = active_equalities_; i < Active(); ++i) {
    if (f_.r(i) <= settings_.tolerance) continue;
    const double ratio = f_.u(i) / f_.r(i);
    if (ratio < *step) {
      *step = ratio;
      drop = i;
    }
  }
  return drop;
}

template <class Factors>
std::optional<DenseQpStatus> ActiveSetSolver<Factors>::AddInequality(int k, int max_iterations) {
  const double tol = settings_.tolerance;
  double u_new = 0.0;  // multiplier of the constraint being added
  EnsureNormal(k);
  for (bool dropped = false;; dropped = true) {
    if (++iterations_ > max_iterations) return DenseQpStatus::kIterationLimit;
    if (dropped) {
      DirectionsAfterDrop();
    } else {
      Directions(k);
    }
    const int q = Active();
    double t1;  // partial step length
    const int drop = BlockingActive(&t1);
    const double zn = f_.z.dot(Normal(k));
    double t2 = kInf;  // full step length
    if (DirectionIsLong(k) && zn > tol * tol) {
      t2 = -Slack(k) / zn;
    }
    if (t1 == kInf && t2 == kInf) return DenseQpStatus::kInfeasible;
    if (t2 == kInf) {  // dual-only step, then drop
      if (q > 0) f_.u.head(q) -= t1 * f_.r.head(q);
      u_new += t1;
      DropFromFactorization(drop);
      continue;
    }
    const double t = std::min(t1, t2);
    f_.x -= t * f_.z;
    if (q > 0) f_.u.head(q) -= t * f_.r.head(q);
    u_new += t;
    if (t2 <= t1) {
      AddToFactorization();
      Activate(k, u_new);
      return std::nullopt;
    }
    DropFromFactorization(drop);
  }
}

template <class Factors>
void ActiveSetSolver<Factors>::Run(DenseQpResult* out) {
  if (!Initialize()) return Finish(DenseQpStatus::kNumericalError, -1, out);
  const int max_iterations =
      settings_.max_iterations > 0 ? settings_.max_iterations : 5 * (N() + m_ + p_) + 20;
  // Equalities first: each becomes active with a multiplier of either sign.
  if (const int inconsistent = AddEqualities(); inconsistent >= 0) {
    return Finish(DenseQpStatus::kInfeasible, inconsistent, out);
  }
  if (impossible_row_ >= 0) return Finish(DenseQpStatus::kInfeasible, impossible_row_, out);
  while (true) {
    const int k = MostViolated();
    if (k < 0) return Finish(DenseQpStatus::kOptimal, -1, out);
    if (const std::optional<DenseQpStatus> stop = AddInequality(k, max_iterations)) {
      return Finish(*stop, k, out);
    }
  }
}

template <class Factors>
void Solve(const DenseQp& qp, const DenseQpSettings& settings, DenseQpWorkspace* workspace,
           Factors* factors, DenseQpResult* result) {
  ActiveSetSolver<Factors>(qp, settings, workspace, factors).Run(result);
}

template <int N>
void SolveFixed(const DenseQp& qp, const DenseQpSettings& settings, DenseQpWorkspace* workspace,
                DenseQpResult* result) {
  FixedFactors<N> factors;
  Solve(qp, settings, workspace, &factors, result);
}

}  // namespace

void SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings, DenseQpWorkspace* workspace,
                  DenseQpResult* result) {
  using FixedSolve =
      void (*)(const DenseQp&, const DenseQpSettings&, DenseQpWorkspace*, DenseQpResult*);
  static constexpr FixedSolve kFixed[] = {
      nullptr,         &SolveFixed<1>,  &SolveFixed<2>, &SolveFixed<3>, &SolveFixed<4>,
      &SolveFixed<5>,  &SolveFixed<6>,  &SolveFixed<7>, &SolveFixed<8>, &SolveFixed<9>,
      &SolveFixed<10>, &SolveFixed<11>, &SolveFixed<12>};
  const int n = static_cast<int>(qp.gradient.size());
  if (n >= 1 && n <= 12) {
    kFixed[n](qp, settings, workspace, result);
  } else if (n <= 16) {
    SmallFactors<16> factors;
    Solve(qp, settings, workspace, &factors, result);
  } else {
    WorkspaceFactors factors(*workspace);
    Solve(qp, settings, workspace, &factors, result);
  }
}

DenseQpResult SolveDenseQp(const DenseQp& qp, const DenseQpSettings& settings) {
  DenseQpWorkspace workspace;
  DenseQpResult result;
  SolveDenseQp(qp, settings, &workspace, &result);
  return result;
}

}  // namespace tactforce::planner
