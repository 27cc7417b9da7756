// Kinematics for the fits: three-point differences, measured columns, and
// local-polynomial smoothing with a data-driven window.
#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "internal.h"

namespace tactforce::inertia::internal {

Vec3 LogSO3(const Eigen::Matrix3d& R) {
  Eigen::Quaterniond q(R);
  q.normalize();
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const Vec3 v = q.vec();
  const double s = v.norm();
  if (s < 1e-12) return 2.0 * v;  // angle ~ 2 s
  const double angle = 2.0 * std::atan2(s, q.w());
  return angle / s * v;
}

Eigen::Matrix3d ExpSO3(const Vec3& w) {
  const double a = w.norm();
  if (a < 1e-12) return Eigen::Matrix3d::Identity() + Skew(w);
  return Eigen::AngleAxisd(a, w / a).toRotationMatrix();
}

Matrix6x10 Regressor(const Vec3& w, const Vec3& dw, const Vec3& amg) {
  Matrix6x10 Y = Matrix6x10::Zero();
  Y.block<3, 1>(0, 0) = amg;
  Y.block<3, 3>(0, 1) = Skew(dw) + Skew(w) * Skew(w);
  Y.block<3, 3>(3, 1) = -Skew(amg);
  auto L = [](const Vec3& x) {
    Eigen::Matrix<double, 3, 6> l;
    l << x(0), 0, 0, x(1), x(2), 0,  //
        0, x(1), 0, x(0), 0, x(2),   //
        0, 0, x(2), 0, x(0), x(1);
    return l;
  };
  Y.block<3, 6>(3, 4) = L(dw) + Skew(w) * L(w);
  return Y;
}

Vector6d SampleWrench(const InertiaSample& s, ForceSource source) {
  Vector6d b;
  if (source == ForceSource::kWrench) {
    b << s.force, s.torque;
    return b;
  }
  Vec3 f = Vec3::Zero(), tau = Vec3::Zero();
  for (const ContactReading& c : s.contacts) {
    f += c.force;
    tau += c.point.cross(c.force);
  }
  b << f, tau;
  return b;
}

bool WrenchCovariance(const InertiaSample& s, ForceSource source, const InertiaNoise& noise,
                      Matrix6d* cov) {
  cov->setZero();
  if (source == ForceSource::kWrench) {
    const double sf = s.force_sigma > 0 ? s.force_sigma : noise.force_sigma;
    const double st = s.torque_sigma > 0 ? s.torque_sigma : noise.torque_sigma;
    if (!(sf > 0 && st > 0)) return false;
    cov->topLeftCorner<3, 3>() = sf * sf * Eigen::Matrix3d::Identity();
    cov->bottomRightCorner<3, 3>() = st * st * Eigen::Matrix3d::Identity();
    return true;
  }
  for (const ContactReading& c : s.contacts) {
    const double sg = c.sigma > 0 ? c.sigma : noise.force_sigma;
    if (c.force.squaredNorm() == 0.0) continue;  // broken contact: a known zero
    if (!(sg > 0)) return false;
    Eigen::Matrix<double, 6, 3> G;
    G << Eigen::Matrix3d::Identity(), Skew(c.point);
    *cov += sg * sg * G * G.transpose();
  }
  return true;
}

std::vector<KinPoint> FiniteDifferenceKinematics(const InertiaSamples& s, const Vec3& g,
                                                 InterruptPoll* poll) {
  std::vector<KinPoint> out;
  const auto& x = s.samples;
  const int n = static_cast<int>(x.size());
  out.reserve(std::max(0, n - 2));
  for (int k = 1; k + 1 < n; ++k) {
    if (poll->Tick()) break;
    const Eigen::Matrix3d R0 = x[k - 1].orientation.toRotationMatrix();
    const Eigen::Matrix3d R1 = x[k].orientation.toRotationMatrix();
    const Eigen::Matrix3d R2 = x[k + 1].orientation.toRotationMatrix();
    const double hb = x[k].t - x[k - 1].t, hf = x[k + 1].t - x[k].t;
    const Vec3 rb = LogSO3(R0.transpose() * R1) / hb, rf = LogSO3(R1.transpose() * R2) / hf;
    KinPoint p;
    p.index = k;
    p.t = x[k].t;
    p.R = R1;
    p.w = (hf * rb + hb * rf) / (hb + hf);
    p.dw = 2.0 * (rf - rb) / (hb + hf);
    const Vec3 a =
        2.0 *
        ((x[k + 1].position - x[k].position) / hf - (x[k].position - x[k - 1].position) / hb) /
        (hb + hf);
    p.a_minus_g = R1.transpose() * (a - g);
    out.push_back(p);
  }
  return out;
}

std::vector<KinPoint> MeasuredKinematicsPoints(const InertiaSamples& s, const Vec3& g,
                                               InterruptPoll* poll) {
  std::vector<KinPoint> out;
  out.reserve(s.samples.size());
  for (int k = 0; k < static_cast<int>(s.samples.size()); ++k) {
    if (poll->Tick()) break;
    const InertiaSample& x = s.samples[k];
    KinPoint p;
    p.index = k;
    p.t = x.t;
    p.R = x.orientation.toRotationMatrix();
    p.w = x.kinematics->angular_velocity;
    p.dw = x.kinematics->angular_acceleration;
    p.a_minus_g = p.R.transpose() * (x.kinematics->acceleration - g);
    out.push_back(p);
  }
  return out;
}

namespace {

// Weights of a window depend only on the relative sample times: on a
// uniform grid, only on (window, degree, k - lo). Small per-thread cache.
struct WeightKey {
  int window, degree, offset;
  double h;
  bool operator==(const WeightKey& o) const {
    return window == o.window && degree == o.degree && offset == o.offset && h == o.h;
  }
};

struct WeightKeyHash {
  size_t operator()(const WeightKey& k) const {
    size_t h = std::hash<double>()(k.h);
    for (int v : {k.window, k.degree, k.offset}) h = h * 1000003u ^ static_cast<size_t>(v);
    return h;
  }
};

bool UniformAround(const std::vector<double>& t, int lo, int w, double* h) {
  const double dt = t[lo + 1] - t[lo];
  for (int j = lo + 1; j < lo + w; ++j) {
    if (std::abs((t[j] - t[j - 1]) - dt) > 1e-9 * dt) return false;
  }
  *h = dt;
  return true;
}

Eigen::MatrixXd ComputeWeights(const std::vector<double>& t, int k, int w, int deg, int lo);

}  // namespace

Eigen::MatrixXd LocalPolyWeights(const std::vector<double>& t, int k, int window, int degree,
                                 int* lo_out) {
  const int n = static_cast<int>(t.size());
  const int w = std::max(1, std::min(window, n));
  const int deg = std::max(0, std::min(degree, w - 1));
  const int lo = std::clamp(k - w / 2, 0, n - w);
  *lo_out = lo;
  if (w == 1) return Eigen::MatrixXd::Ones(1, 1);
  double dt = 0;
  if (!UniformAround(t, lo, w, &dt)) return ComputeWeights(t, k, w, deg, lo);
  thread_local std::unordered_map<WeightKey, Eigen::MatrixXd, WeightKeyHash> cache;
  const WeightKey key{w, deg, k - lo, dt};
  if (auto it = cache.find(key); it != cache.end()) return it->second;
  Eigen::MatrixXd m = ComputeWeights(t, k, w, deg, lo);
  if (cache.size() > 100000) cache.clear();
  cache.emplace(key, m);
  return m;
}

namespace {

Eigen::MatrixXd ComputeWeights(const std::vector<double>& t, int k, int w, int deg, int lo) {
  const int rows = std::min(deg, 2) + 1;
  const double h = std::max(t[k] - t[lo], t[lo + w - 1] - t[k]);
  Eigen::MatrixXd V(w, deg + 1);
  for (int j = 0; j < w; ++j) {
    const double tau = (t[lo + j] - t[k]) / h;
    double p = 1.0;
    for (int i = 0; i <= deg; ++i) V(j, i) = p, p *= tau;
  }
  const Eigen::MatrixXd G = V.transpose() * V;
  Eigen::MatrixXd C = G.ldlt().solve(V.transpose());  // (deg+1) x w
  Eigen::MatrixXd out(rows, w);
  out.row(0) = C.row(0);
  if (rows > 1) out.row(1) = C.row(1) / h;
  if (rows > 2) out.row(2) = C.row(2) * (2.0 / (h * h));
  return out;
}

}  // namespace

Eigen::MatrixXd SmoothSeries(const std::vector<double>& t, const Eigen::MatrixXd& values,
                             int window, int degree, InterruptPoll* poll) {
  Eigen::MatrixXd out = Eigen::MatrixXd::Zero(values.rows(), values.cols());
  for (int k = 0; k < values.rows(); ++k) {
    if (poll->Tick(4)) break;
    int lo = 0;
    const Eigen::MatrixXd W = LocalPolyWeights(t, k, window, degree, &lo);
    out.row(k) = W.row(0) * values.middleRows(lo, W.cols());
  }
  return out;
}

namespace {

struct Candidate {
  int window;
  int degree;
};

// A vector signal seen from each sample k: values of samples j near k in
// the chart of sample k (differences for positions, log(R_k^T R_j) for
// orientations). Computed lazily for one k at a time (O(window) memory).
class Charted {
 public:
  static Charted Positions(const std::vector<Vec3>& p, int span) {
    return Charted(&p, nullptr, span);
  }
  static Charted Rotations(const std::vector<Eigen::Matrix3d>& R, int span) {
    return Charted(nullptr, &R, span);
  }

  Vec3 At(int k, int j) const {
    if (k != k_) Fill(k);
    return cache_[j - lo_];
  }

 private:
  Charted(const std::vector<Vec3>* p, const std::vector<Eigen::Matrix3d>* R, int span)
      : p_(p), R_(R), n_(static_cast<int>(p ? p->size() : R->size())), span_(std::min(span, n_)) {}

  void Fill(int k) const {
    k_ = k;
    lo_ = std::clamp(k - span_ / 2, 0, n_ - span_);
    cache_.resize(span_);
    if (p_) {
      for (int j = 0; j < span_; ++j) cache_[j] = (*p_)[lo_ + j] - (*p_)[k];
    } else {
      const Eigen::Matrix3d Rt = (*R_)[k].transpose();
      for (int j = 0; j < span_; ++j) cache_[j] = LogSO3(Rt * (*R_)[lo_ + j]);
    }
  }

  const std::vector<Vec3>* p_;
  const std::vector<Eigen::Matrix3d>* R_;
  int n_, span_;
  mutable int k_ = -1, lo_ = 0;
  mutable std::vector<Vec3> cache_;
};

struct FitResult {
  Candidate chosen{1, 0};
  double sigma2 = 0;  // noise variance used
  bool estimated = false;
  std::vector<Vec3> d[3];      // value, 1st, 2nd derivative per sample
  std::vector<double> wsq[3];  // sum of squared weights per sample
};

constexpr int kMaxWindow = 101;

// Applies weights row r at k.
Vec3 Apply(const Charted& c, int k, const Eigen::MatrixXd& W, int lo, int r) {
  Vec3 acc = Vec3::Zero();
  for (int j = 0; j < W.cols(); ++j) acc += W(r, j) * c.At(k, lo + j);
  return acc;
}

FitResult Final(const std::vector<double>& t, const Charted& c, Candidate cand,
                InterruptPoll* poll) {
  const int n = static_cast<int>(t.size());
  FitResult f;
  f.chosen = cand;
  for (int r = 0; r < 3; ++r) f.d[r].assign(n, Vec3::Zero()), f.wsq[r].assign(n, 0.0);
  for (int k = 0; k < n; ++k) {
    if (poll->Tick(8)) break;
    int lo = 0;
    const Eigen::MatrixXd W = LocalPolyWeights(t, k, cand.window, cand.degree, &lo);
    for (int r = 0; r < W.rows(); ++r) {
      f.d[r][k] = Apply(c, k, W, lo, r);
      f.wsq[r][k] = W.row(r).squaredNorm();
    }
  }
  return f;
}

// The short quartic fit whose residuals measure a signal's noise.
constexpr Candidate kRoughnessFit{7, 4};

// Noise variance per component of a signal from its roughness: the
// residual of a local polynomial fit `e` at each sample, divided by its
// expected value per unit noise variance (1 - 2 w_kk + |w|^2 per component),
// so white noise of any level is recovered without bias while a smooth
// signal (its variation well inside the fit's degree over the window)
// contributes only its fit error.
double RoughnessVariance(const std::vector<double>& t, const Charted& c, Candidate e,
                         InterruptPoll* poll) {
  const int n = static_cast<int>(t.size());
  e.window = std::min(e.window, n);
  e.degree = std::min(e.degree, e.window - 1);
  double num = 0, den = 0;
  for (int k = 0; k < n; ++k) {
    if (poll->Tick(4)) break;
    int lo = 0;
    const Eigen::MatrixXd W = LocalPolyWeights(t, k, e.window, e.degree, &lo);
    const Vec3 r = c.At(k, k) - Apply(c, k, W, lo, 0);
    const double wkk = W(0, k - lo);
    num += r.squaredNorm();
    den += 3.0 * std::max(1e-12, 1.0 - 2.0 * wkk + W.row(0).squaredNorm());
  }
  return den > 0 ? num / den : 0.0;
}

// Chooses the window/degree minimising an unbiased estimate of the mean
// squared error of derivative `order` (0 or 2) of the signal:
//   MSE_c ~ mean |d_c - d_ref|^2 - sigma^2 (|w_ref|^2 - 2 w_c . w_ref)
// where the reference is the raw data (order 0) or a short quartic fit
// (order 2): nearly unbiased, so the first term measures bias^2 plus the
// known noise terms. sigma2 < 0: estimated from the reference residuals.
FitResult SelectAndFit(const std::vector<double>& t, const Charted& c, int order, double sigma2,
                       int fixed_window, InterruptPoll* poll) {
  const int n = static_cast<int>(t.size());
  if (fixed_window > 0) {
    FitResult f = Final(t, c, {fixed_window, 3}, poll);
    f.sigma2 = std::max(sigma2, 0.0);
    return f;
  }
  const Candidate ref =
      order == 0 ? Candidate{1, 0} : Candidate{std::min(7, n), std::min(4, std::min(7, n) - 1)};
  std::vector<Candidate> cands;
  if (order == 0) cands.push_back({1, 0});
  for (int w : {5, 7, 9, 11, 15, 21, 31, 41, 51, 71, 101}) {
    if (w > n) continue;
    if (w >= 7) cands.push_back({w, 4});
    cands.push_back({w, 2});
  }
  if (cands.empty()) cands.push_back(ref);
  bool estimated = false;
  if (sigma2 < 0) {
    sigma2 = RoughnessVariance(t, c, order == 0 ? kRoughnessFit : ref, poll);
    estimated = true;
  }
  const int nc = static_cast<int>(cands.size());
  std::vector<double> sse(nc, 0.0), refsq(nc, 0.0), cross(nc, 0.0);
  std::vector<char> valid(nc, 1);
  for (int k = 0; k < n; ++k) {
    if (poll->Tick(nc)) break;
    int lo_r = 0;
    const Eigen::MatrixXd Wr = LocalPolyWeights(t, k, ref.window, ref.degree, &lo_r);
    if (Wr.rows() <= order) return Final(t, c, ref, poll);
    const Vec3 dr = Apply(c, k, Wr, lo_r, order);
    const double wr2 = Wr.row(order).squaredNorm();
    for (int i = 0; i < nc; ++i) {
      if (!valid[i]) continue;
      int lo_c = 0;
      const Eigen::MatrixXd Wc = LocalPolyWeights(t, k, cands[i].window, cands[i].degree, &lo_c);
      if (Wc.rows() <= order) {
        valid[i] = 0;
        continue;
      }
      sse[i] += (Apply(c, k, Wc, lo_c, order) - dr).squaredNorm();
      refsq[i] += wr2;
      for (int j = 0; j < Wc.cols(); ++j) {
        const int jj = lo_c + j - lo_r;
        if (jj >= 0 && jj < Wr.cols()) cross[i] += Wc(order, j) * Wr(order, jj);
      }
    }
  }
  double best = std::numeric_limits<double>::infinity();
  Candidate chosen = cands.front();
  for (int i = 0; i < nc; ++i) {
    if (!valid[i]) continue;
    const double mse = sse[i] / (3.0 * n) - sigma2 * (refsq[i] - 2.0 * cross[i]) / n;
    if (mse < best) best = mse, chosen = cands[i];
  }
  FitResult f = Final(t, c, chosen, poll);
  f.sigma2 = sigma2;
  f.estimated = estimated;
  return f;
}

std::string Describe(const char* what, const FitResult& f) {
  return absl::StrFormat("%s: local polynomial window %d, degree %d (noise sigma %.3g%s)", what,
                         f.chosen.window, f.chosen.degree, std::sqrt(f.sigma2),
                         f.estimated ? ", estimated" : "");
}

struct SeriesNoise {
  const char* name;
  const char* unit;
  double sigma;   // given; 0 = unknown
  bool estimate;  // estimate an unknown sigma from the series' roughness
};

// Smooths a measured series (object or world frame) in place when it is
// noisy and sets the per-sample variance of the smoothed values. An unknown
// sigma of a regressor series (the accelerations) is estimated from the
// series' roughness, so the errors-in-variables weighting and bias
// correction see it; other unknown sigmas leave the series as measured
// (returns false) unless a fixed window is asked for.
bool SmoothMeasuredSeries(const std::vector<double>& t, const SeriesNoise& noise, int fixed_window,
                          std::vector<Vec3>* series, std::vector<double>* variance,
                          std::vector<std::string>* notes, InterruptPoll* poll) {
  const bool estimated = !(noise.sigma > 0) && noise.estimate;
  if (!(noise.sigma > 0) && !estimated && fixed_window <= 0) return false;
  const int n = static_cast<int>(series->size());
  const Charted c = Charted::Positions(*series, kMaxWindow);
  const double sigma2 =
      estimated ? RoughnessVariance(t, c, kRoughnessFit, poll) : noise.sigma * noise.sigma;
  FitResult f = SelectAndFit(t, c, 0, sigma2, fixed_window, poll);
  f.estimated = estimated;
  variance->assign(n, 0.0);
  for (int k = 0; k < n; ++k) (*series)[k] += f.d[0][k], (*variance)[k] = f.sigma2 * f.wsq[0][k];
  if (notes) notes->push_back(Describe(noise.name, f));
  if (notes && estimated) {
    notes->push_back(
        absl::StrFormat("%s noise: sigma %.3g %s estimated from the data (roughness against a "
                        "local quartic over %d samples; "
                        "give it to override)",
                        noise.name, std::sqrt(f.sigma2), noise.unit, kRoughnessFit.window));
  }
  return true;
}

// Measured kinematics: the orientations smoothed on SO(3) (their own noise
// level), with each point's variance.
void SmoothMeasuredOrientations(const std::vector<double>& t, const std::vector<Eigen::Matrix3d>& R,
                                double sigma, int fixed_window, std::vector<KinPoint>* m,
                                std::vector<std::string>* notes, InterruptPoll* poll) {
  const FitResult f =
      SelectAndFit(t, Charted::Rotations(R, kMaxWindow), 0, sigma * sigma, fixed_window, poll);
  for (size_t k = 0; k < m->size(); ++k) {
    (*m)[k].R = R[k] * ExpSO3(f.d[0][k]);
    (*m)[k].var_rot = f.sigma2 * f.wsq[0][k];
  }
  if (notes) notes->push_back(Describe("orientation", f));
}

}  // namespace

std::vector<KinPoint> SmoothedKinematics(const InertiaSamples& s, const Vec3& g,
                                         const InertiaNoise& noise, int fixed_window,
                                         std::vector<std::string>* notes, InterruptPoll* poll) {
  const int n = static_cast<int>(s.samples.size());
  std::vector<double> t(n);
  std::vector<Vec3> p(n);
  std::vector<Eigen::Matrix3d> R(n);
  for (int k = 0; k < n; ++k) {
    if (poll->Tick()) return {};
    t[k] = s.samples[k].t;
    p[k] = s.samples[k].position;
    R[k] = s.samples[k].orientation.toRotationMatrix();
  }
  if (s.HasKinematics()) {
    std::vector<KinPoint> m = MeasuredKinematicsPoints(s, g, poll);
    if (poll->stopped()) return m;
    auto smooth = [&](const char* name, double sigma, bool estimate, const char* unit, auto get,
                      auto set, double KinPoint::*var) {
      std::vector<Vec3> series(n);
      for (int k = 0; k < n; ++k) series[k] = get(k);
      std::vector<double> variance;
      if (!SmoothMeasuredSeries(t, {name, unit, sigma, estimate}, fixed_window, &series, &variance,
                                notes, poll))
        return;
      for (int k = 0; k < n; ++k) set(k, series[k]), m[k].*var = variance[k];
    };
    std::vector<Vec3> acc(n);
    for (int k = 0; k < n; ++k) acc[k] = s.samples[k].kinematics->acceleration;
    smooth(
        "measured angular velocity", noise.angular_velocity_sigma, false, "rad/s",
        [&](int k) { return m[k].w; }, [&](int k, const Vec3& v) { m[k].w = v; }, &KinPoint::var_w);
    smooth(
        "measured angular acceleration", noise.angular_acceleration_sigma, true, "rad/s^2",
        [&](int k) { return m[k].dw; }, [&](int k, const Vec3& v) { m[k].dw = v; },
        &KinPoint::var_dw);
    smooth(
        "measured acceleration", noise.linear_acceleration_sigma, true, "m/s^2",
        [&](int k) { return acc[k]; }, [&](int k, const Vec3& v) { acc[k] = v; }, &KinPoint::var_a);
    if (noise.orientation_sigma > 0)
      SmoothMeasuredOrientations(t, R, noise.orientation_sigma, fixed_window, &m, notes, poll);
    for (int k = 0; k < n; ++k) m[k].a_minus_g = m[k].R.transpose() * (acc[k] - g);
    return m;
  }
  const double sp2 = noise.position_sigma > 0 ? noise.position_sigma * noise.position_sigma : -1.0;
  const double sr2 =
      noise.orientation_sigma > 0 ? noise.orientation_sigma * noise.orientation_sigma : -1.0;
  const FitResult fp =
      SelectAndFit(t, Charted::Positions(p, kMaxWindow), 2, sp2, fixed_window, poll);
  const FitResult fr =
      SelectAndFit(t, Charted::Rotations(R, kMaxWindow), 2, sr2, fixed_window, poll);
  if (poll->stopped()) return {};
  if (notes) {
    notes->push_back(Describe("kinematics from positions", fp));
    notes->push_back(Describe("kinematics from orientations", fr));
  }
  std::vector<KinPoint> out;
  out.reserve(n);  // filled as polled (no unpolled initialisation of n points)
  for (int k = 0; k < n; ++k) {
    if (poll->Tick()) break;
    KinPoint& q = out.emplace_back();
    q.index = k;
    q.t = t[k];
    q.R = R[k] * ExpSO3(fr.d[0][k]);
    q.w = fr.d[1][k];
    q.dw = fr.d[2][k];
    q.a_minus_g = q.R.transpose() * (fp.d[2][k] - g);
    q.var_a = fp.sigma2 * fp.wsq[2][k];
    q.var_w = fr.sigma2 * fr.wsq[1][k];
    q.var_dw = fr.sigma2 * fr.wsq[2][k];
    q.var_rot = fr.sigma2 * fr.wsq[0][k];
  }
  return out;
}

Vector10d ParameterScale(double m0, double l) {
  Vector10d s;
  s << m0, m0 * l, m0 * l, m0 * l, m0 * l * l, m0 * l * l, m0 * l * l, m0 * l * l, m0 * l * l,
      m0 * l * l;
  return s;
}

}  // namespace tactforce::inertia::internal
