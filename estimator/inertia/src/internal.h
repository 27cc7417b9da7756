// Shared internals of the inertia fits (not installed).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "absl/status/statusor.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/hull.h"
#include "tactforce/inertia/types.h"
#include "tactforce/planner/skew.h"

namespace tactforce::inertia::internal {

// The status every interrupted fit returns: absl::Cancelled("interrupted").
absl::Status Interrupted();

// Polls InertiaOptions::interrupt from the loops of a fit. Tick(work)
// counts work (about one sample's worth per unit) and calls the callback
// once per kInterruptStride units; Check() calls it now. Once the callback
// has returned true every later call returns true, so a helper can stop its
// loop early (its output is then incomplete) and the method, which checks
// stopped() after each helper, returns Interrupted(). An empty callback
// never stops.
class InterruptPoll {
 public:
  // A few thousand samples' worth of work between polls: the callback's cost
  // is negligible against the loops, and even the costliest loops
  // (factor-graph AutoDiff, kinematics window selection) see an interrupt
  // within a small fraction of a fit.
  static constexpr int64_t kInterruptStride = 2048;

  explicit InterruptPoll(std::function<bool()> interrupt) : interrupt_(std::move(interrupt)) {}
  bool Tick(int64_t work = 1) {
    if (stopped_) return true;
    if (!interrupt_) return false;
    pending_ += work;
    if (pending_ < kInterruptStride) return false;
    return Check();
  }
  bool Check() {
    pending_ = 0;
    if (!stopped_ && interrupt_ && interrupt_()) stopped_ = true;
    return stopped_;
  }
  bool stopped() const { return stopped_; }

 private:
  std::function<bool()> interrupt_;
  int64_t pending_ = 0;
  bool stopped_ = false;
};

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix6x10 = Eigen::Matrix<double, 6, 10>;
using Matrix10d = Eigen::Matrix<double, 10, 10>;

using planner::Skew;  // the cross-product matrix
Vec3 LogSO3(const Eigen::Matrix3d& R);
Eigen::Matrix3d ExpSO3(const Vec3& w);

// Newton-Euler regressor in the object frame: [F; tau] = Y pi with pi the
// standard parameters (about the origin); a_minus_g = R^T (a_world - g).
Matrix6x10 Regressor(const Vec3& w, const Vec3& dw, const Vec3& a_minus_g);
// Measured wrench (F, tau about the origin) of a sample.
Vector6d SampleWrench(const InertiaSample& s, ForceSource source);
// Wrench covariance from the noise model (per-sample sigmas win over the
// options). Returns false when no sigma is known for this sample.
bool WrenchCovariance(const InertiaSample& s, ForceSource source, const InertiaNoise& noise,
                      Matrix6d* cov);

// Kinematics at one sample, object frame, with the per-component variances
// of the estimates (for errors-in-variables weighting; 0 = exact/unknown).
struct KinPoint {
  int index = 0;
  double t = 0;
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Vec3 w = Vec3::Zero(), dw = Vec3::Zero(), a_minus_g = Vec3::Zero();
  double var_w = 0, var_dw = 0, var_a = 0, var_rot = 0;
};

// ValidateInertiaSamples (samples.h), returning Interrupted() when `poll`
// fires; in the same pass, when `normalized` is not null, a copy of the
// samples with unit quaternions into it (complete when OK is returned).
absl::Status ValidateInertiaSamples(const InertiaSamples& s, InterruptPoll* poll,
                                    InertiaSamples* normalized = nullptr);

// The loops below poll `poll` and stop early (incomplete output) once it
// has fired; callers check poll->stopped().

// Three-point differences at samples 1..N-2 (BASELINE_LS).
std::vector<KinPoint> FiniteDifferenceKinematics(const InertiaSamples& s, const Vec3& g,
                                                 InterruptPoll* poll);
// The measured columns, unsmoothed.
std::vector<KinPoint> MeasuredKinematicsPoints(const InertiaSamples& s, const Vec3& g,
                                               InterruptPoll* poll);

// Weights of a local polynomial fit of `degree` over `window` samples around
// sample k (window shifted inside the data at the ends): row r (0..min(deg,2))
// gives the r-th derivative at t_k as sum_j W(r, j) y_{lo + j}.
Eigen::MatrixXd LocalPolyWeights(const std::vector<double>& t, int k, int window, int degree,
                                 int* lo);

// Smooths each column of `values` (rows = samples) with a local polynomial.
Eigen::MatrixXd SmoothSeries(const std::vector<double>& t, const Eigen::MatrixXd& values,
                             int window, int degree, InterruptPoll* poll);

// CONSTRAINED kinematics: from poses by local-polynomial fits (position, and
// orientation in a local chart), window/degree chosen per signal by an
// unbiased risk estimate (noise level given or estimated), or
// `fixed_window` > 0; or, with measured kinematics, those columns smoothed
// when their noise is given. Notes describe the choices.
std::vector<KinPoint> SmoothedKinematics(const InertiaSamples& s, const Vec3& g,
                                         const InertiaNoise& noise, int fixed_window,
                                         std::vector<std::string>* notes, InterruptPoll* poll);

// Scale of the standard parameters: [m0, m0 l x3, m0 l^2 x6].
Vector10d ParameterScale(double m0, double length);

// Output of a method, completed by FitInertia.
struct MethodOutput {
  Vector10d pi = Vector10d::Zero();
  Matrix10d cov = Matrix10d::Zero();    // covariance of pi; zero if unknown
  Matrix10d info = Matrix10d::Zero();   // Y^T W Y (excitation analysis)
  Vector10d scale = Vector10d::Ones();  // parameter scale for the analysis
  double rms_force = 0, rms_torque = 0;
  int iterations = 0;
  int samples_used = 0;
  std::vector<std::string> notes;
  // DENSITY only.
  std::vector<double> densities, density_se;
  double regularization = 0;
  std::string regularization_rule;
  double heldout_ratio = 0;
  double heldout_z = 0;
  // The held-out difference between DENSITY's and the free fit's predicted
  // wrenches in the units of the fitted parameters: the RMS force difference
  // over m |a - g| (a relative mass error) and the RMS torque difference
  // over m |a - g| (a CoM displacement, m); the mesh's bounding-box
  // diagonal (m) is the object's size they are judged against.
  double heldout_mass_equivalent = 0, heldout_com_equivalent = 0, mesh_size = 0;
  // The mesh test: the first-order Riemannian distance between the
  // densities the regions can carry and the free fit's confidence
  // ellipsoid (chi^2 <= mesh_chi2_bound above its minimum), and the least
  // chi^2 excess of a realizable density over the free fit.
  double mesh_distance = 0, mesh_chi2_excess = 0, mesh_chi2_bound = 0;
  // Radii of gyration of the density answer along its principal axes (m),
  // to state the tolerance as a CoM displacement.
  Vec3 gyration_radii = Vec3::Zero();
};

absl::StatusOr<MethodOutput> FitBaselineLs(const InertiaSamples& s, const InertiaOptions& o);
absl::StatusOr<MethodOutput> FitConstrained(const InertiaSamples& s, const InertiaOptions& o,
                                            const ConvexHull* hull);
// DENSITY on the regions of o.mesh, complete: besides the output, `fit`
// receives the mesh check, the region model, the densities, the strength
// and the mesh test's verdict (density_realizable, or mesh_contradicted with
// mesh_contradiction; FitInertia then falls back to CONSTRAINED). The last
// two notes are the held-out note and the mesh test's.
absl::StatusOr<MethodOutput> FitDensity(const InertiaSamples& s, const InertiaOptions& o,
                                        InertiaFit* fit);
absl::StatusOr<MethodOutput> FitFactorGraph(const InertiaSamples& s, const InertiaOptions& o,
                                            const ConvexHull* hull);

// Residual RMS (force, torque) of pi on kinematics/wrenches.
void ResidualRms(const std::vector<KinPoint>& kin, const std::vector<Vector6d>& wrench,
                 const Vector10d& pi, InterruptPoll* poll, double* rms_force, double* rms_torque);

// Least squares min |Y x - b| over many rows, added in any number of calls:
// a stacked (tall-skinny) Householder QR that keeps only a (cols+1)-square
// upper triangle T = [R, q; 0, rho] of [Y b] (R^T R = Y^T Y, R^T q = Y^T b,
// rho^2 = the least residual sum of squares), so memory is O(chunk) and
// callers can poll between rows.
class StackedLeastSquares {
 public:
  explicit StackedLeastSquares(int cols);
  void Add(const Eigen::Ref<const Eigen::MatrixXd>& Y, const Eigen::Ref<const Eigen::VectorXd>& b);
  const Eigen::MatrixXd& Triangle();  // T after all rows added so far

 private:
  static constexpr int kChunkRows = 4096;
  void Flush();
  int cols_;
  Eigen::MatrixXd buffer_;  // rows 0..cols: the triangle; then the pending rows
  int rows_ = 0;            // pending rows
  Eigen::MatrixXd triangle_;
};

// Least squares with column scaling from the 11 x 11 triangle of
// StackedLeastSquares(10); minimum-norm (in scaled parameters) when rank
// deficient (relative singular value below 1e-10). Returns pi.
Vector10d ScaledLeastSquares(const Eigen::MatrixXd& triangle, const Vector10d& scale, int* rank);

// S (S A S)^+ S with S = diag(scale): the pseudo-inverse of a symmetric
// positive semi-definite information matrix A computed in scaled
// coordinates; eigenvalues below relative_tolerance * the largest are
// dropped (unidentifiable directions get zero variance).
Matrix10d ScaledPseudoInverse(const Matrix10d& A, const Vector10d& scale,
                              double relative_tolerance);

// Rough mass and length scale from an unconstrained estimate (fallbacks
// when it is unphysical).
void RoughScale(const Vector10d& pi, const ConvexHull* hull, double* m0, double* length);

}  // namespace tactforce::inertia::internal
