// Shared internals of the inertia fits (not installed).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "absl/status/statusor.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/hull.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia::internal {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;
using Matrix6x10 = Eigen::Matrix<double, 6, 10>;
using Matrix10d = Eigen::Matrix<double, 10, 10>;

Eigen::Matrix3d Skew(const Vec3& v);
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

// Three-point differences at samples 1..N-2 (BASELINE_LS).
std::vector<KinPoint> FiniteDifferenceKinematics(const InertiaSamples& s, const Vec3& g);
// The measured columns, unsmoothed.
std::vector<KinPoint> MeasuredKinematicsPoints(const InertiaSamples& s, const Vec3& g);

// Weights of a local polynomial fit of `degree` over `window` samples around
// sample k (window shifted inside the data at the ends): row r (0..min(deg,2))
// gives the r-th derivative at t_k as sum_j W(r, j) y_{lo + j}.
Eigen::MatrixXd LocalPolyWeights(const std::vector<double>& t, int k, int window, int degree, int* lo);

// Smooths each column of `values` (rows = samples) with a local polynomial.
Eigen::MatrixXd SmoothSeries(const std::vector<double>& t, const Eigen::MatrixXd& values, int window,
                             int degree);

// CONSTRAINED kinematics: from poses by local-polynomial fits (position, and
// orientation in a local chart), window/degree chosen per signal by an
// unbiased risk estimate (noise level given or estimated), or
// `fixed_window` > 0; or, with measured kinematics, those columns smoothed
// when their noise is given. Notes describe the choices.
std::vector<KinPoint> SmoothedKinematics(const InertiaSamples& s, const Vec3& g,
                                         const InertiaNoise& noise, int fixed_window,
                                         std::vector<std::string>* notes);

// Scale of the standard parameters: [m0, m0 l x3, m0 l^2 x6].
Vector10d ParameterScale(double m0, double length);

// Output of a method, completed by FitInertia.
struct MethodOutput {
  Vector10d pi = Vector10d::Zero();
  Matrix10d cov = Matrix10d::Zero();   // covariance of pi; zero if unknown
  Matrix10d info = Matrix10d::Zero();  // Y^T W Y (excitation analysis)
  Vector10d scale = Vector10d::Ones(); // parameter scale for the analysis
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
  // Held-out unweighted RMS residual of DENSITY minus the free fit's,
  // relative to the RMS wrench (how large the misfit is physically).
  double heldout_excess = 0;
};

// Generalised least squares data shared by CONSTRAINED and DENSITY: the
// smoothed kinematics, regressors, wrenches and wrench covariances of the
// samples that give an equation.
struct GlsData {
  std::vector<KinPoint> kin;
  std::vector<Vector6d> wrench;
  std::vector<Matrix6d> wcov;
  std::vector<Matrix6x10> Y;
  bool known = true;  // wrench noise given (else estimated from residuals)
  double floor_f = 0, floor_t = 0;  // variance floors (noise-free data)
  Matrix10d YtY = Matrix10d::Zero();
  Vector10d Ytb = Vector10d::Zero();
};
GlsData PrepareGls(const InertiaSamples& s, const InertiaOptions& o, std::vector<std::string>* notes);

// Normal equations of the whitened problem at the estimate pi: A = sum
// (WY)^T WY, b = sum (WY)^T W w, c = sum |W w|^2, and the first-order
// errors-in-variables bias E[dY^T W dY].
struct GlsSums {
  Matrix10d A = Matrix10d::Zero();
  Matrix10d bias = Matrix10d::Zero();
  Vector10d b = Vector10d::Zero();
  double c = 0;
  int count = 0;
};
// Totals, and optionally per contiguous block of samples (`blocks` >= 1)
// and the whitening matrices W (W^T W = C^-1) per sample.
void AccumulateGls(const GlsData& d, const Vector10d& pi, GlsSums* total, int blocks = 1,
                   std::vector<GlsSums>* per_block = nullptr, std::vector<Matrix6d>* whiteners = nullptr);
// Block of sample k when the samples are cut into `blocks` contiguous blocks.
inline int BlockOf(int k, int n, int blocks) { return static_cast<int>((static_cast<long>(k) * blocks) / n); }
// A - bias when the corrected matrix stays well positive definite (its
// smallest scaled eigenvalue above half of A's), else A.
Matrix10d BiasCorrected(const GlsSums& sums, const Vector10d& scale, bool* applied);

absl::StatusOr<MethodOutput> FitBaselineLs(const InertiaSamples& s, const InertiaOptions& o);
absl::StatusOr<MethodOutput> FitConstrained(const InertiaSamples& s, const InertiaOptions& o,
                                            const ConvexHull* hull);
absl::StatusOr<MethodOutput> FitDensity(const InertiaSamples& s, const InertiaOptions& o,
                                        const RegionModel& regions);
absl::StatusOr<MethodOutput> FitFactorGraph(const InertiaSamples& s, const InertiaOptions& o,
                                            const ConvexHull* hull);

// Residual RMS (force, torque) of pi on kinematics/wrenches.
void ResidualRms(const std::vector<KinPoint>& kin, const std::vector<Vector6d>& wrench,
                 const Vector10d& pi, double* rms_force, double* rms_torque);

// Least squares on stacked rows with column scaling; minimum-norm when rank
// deficient. Returns pi, and fills info = Y^T Y (unscaled) and the residual
// sum of squares.
Vector10d ScaledLeastSquares(const Eigen::MatrixXd& Y, const Eigen::VectorXd& b, const Vector10d& scale,
                             int* rank);

// S (S A S)^+ S with S = diag(scale): the pseudo-inverse of a symmetric
// positive semi-definite information matrix A computed in scaled
// coordinates; eigenvalues below relative_tolerance * the largest are
// dropped (unidentifiable directions get zero variance).
Matrix10d ScaledPseudoInverse(const Matrix10d& A, const Vector10d& scale, double relative_tolerance);

// Rough mass and length scale from an unconstrained estimate (fallbacks
// when it is unphysical).
void RoughScale(const Vector10d& pi, const ConvexHull* hull, double* m0, double* length);

}  // namespace tactforce::inertia::internal
