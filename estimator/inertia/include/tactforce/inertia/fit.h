// Fitting mass, CoM and inertia to poses and forces (Sundaralingam & Hermans
// III-B and beyond). Three methods, one entry point:
//
//   BASELINE_LS   Atkeson, An & Hollerbach 1986: kinematics from three-point
//                 finite differences of the poses (or the measured columns),
//                 optional Savitzky-Golay smoothing (cubic, window 51) of the
//                 wrench and kinematics, ordinary least squares on the 10
//                 standard parameters. Rank-deficient data give the
//                 minimum-norm solution (scaled parameters).
//   FACTOR_GRAPH  the paper: w = [m, c, Lx, Ly, Lz, R in SO(3)] with the
//                 inertia about the object origin R diag(Ly+Lz, Lx+Lz, Lx+Ly) R^T,
//                 dynamics factors from three consecutive poses (eq. 8-19, the
//                 forces of the first of the three), measurement factors on
//                 poses and forces, constraint factors m > 0, c in the hull,
//                 L >= 0 that are costs active only when violated (eq. 35-37),
//                 optional trace prior Tr(P0^-1 P) (eq. 20-21); batch
//                 Levenberg-Marquardt on the sparse problem. Its known
//                 weaknesses are reproduced on purpose (see README).
//   CONSTRAINED   ours: the pseudo-inertia P = U U^T in log-Cholesky
//                 coordinates (Rucker & Wensing 2022), so every estimate is
//                 physically consistent by construction; kinematics from a
//                 local-polynomial smoothing fit; generalised least squares
//                 whose per-sample covariance holds the force noise and the
//                 pose/kinematics noise propagated through the model
//                 (iteratively re-weighted); optional entropic (Bregman) prior;
//                 CoM-in-hull rows as hard constraints (NLopt SLSQP); exact
//                 derivatives, damped Newton. Given a mesh, its
//                 uniform-density inertia scaled to the fitted mass is used
//                 as the prior (eq. 20-21) unless a prior is given.
//   DENSITY       ours, needs a closed mesh: the density is non-negative and
//                 constant over K regions of the solid (density.h), so the
//                 ten standard parameters are linear in the K densities; a
//                 non-negative least squares in K unknowns with the same
//                 noise weighting as CONSTRAINED and a smoothness
//                 regulariser between neighbouring regions whose strength is
//                 chosen by held-out time blocks. Every answer is
//                 density-realizable. When the data contradict the mesh
//                 (every density it can carry is more than 0.03, first-order
//                 Riemannian, from the free fit's 99.9 % confidence
//                 ellipsoid) the fit says so and returns CONSTRAINED's
//                 answer, marked.
//
// No exceptions: bad input is absl::InvalidArgument naming the field, line
// or column. Insufficient excitation is not an error: the result names the
// poorly excited parameter directions.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "tactforce/io/mesh.h"
#include "tactforce/inertia/density.h"
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

enum class InertiaMethod { kBaselineLs, kFactorGraph, kConstrained, kDensity };

// "baseline-ls", "factor-graph", "constrained", "density" (CLI spelling).
const char* ToString(InertiaMethod method);
// Accepts either spelling, case-insensitive, '_' or '-'.
absl::StatusOr<InertiaMethod> ParseInertiaMethod(std::string_view text);

// Which factors and parameterisation FACTOR_GRAPH uses (the ablation of
// Sundaralingam & Hermans, Sec. IV-B, Figs. 7-8, Tables I-IV):
//   kBaselineFg        "Baseline-FG": the inertial variables are the paper's
//                      w_vector = [m, c, H_xx, H_yy, H_zz, H_xy, H_xz, H_yz]
//                      (H about the origin, independent reals in a vector
//                      space) with the pose and force measurement variables;
//                      no constraint factor, no prior (a given prior is
//                      ignored, noted).
//   kNoConstraint      "No C, No G": w = [m, c, L, R in SO(3)] with every
//                      constraint factor off (m > 0, c in the hull and
//                      L >= 0); no prior (ignored, noted).
//   kConstraint        "C, No G": the constraint factors on (the default;
//                      exactly the FACTOR_GRAPH of earlier releases, which
//                      also adds the trace prior when a prior is given).
//   kConstraintPrior   "C + G": plus the trace prior (eq. 20); a prior is
//                      required (InvalidArgument naming `prior`).
enum class FactorGraphVariant { kBaselineFg, kNoConstraint, kConstraint, kConstraintPrior };

// "baseline-fg", "fg-no-c", "fg-c", "fg-c-g" (CLI spelling).
const char* ToString(FactorGraphVariant variant);
// Accepts the CLI spelling, case-insensitive, '_' or '-', and the wire
// spelling FACTOR_GRAPH_VARIANT_* (BASELINE_FG, NO_C, C, C_G).
absl::StatusOr<FactorGraphVariant> ParseFactorGraphVariant(std::string_view text);

struct InertiaPrior {
  InertialParameters params;
  double weight = 1.0;  // >= 0; relative to the data term (in units of chi^2)
};

// Noise levels (standard deviations). 0 means "unknown": the fit then
// estimates the wrench noise from its own residuals.
// Unknown measured linear and angular acceleration sigmas are estimated
// from the series' roughness (CONSTRAINED, DENSITY); the notes name them.
struct InertiaNoise {
  double force_sigma = 0.0;   // N per component: each contact force (contacts) or the wrench force
  double torque_sigma = 0.0;  // N m per component, wrench source only
  double position_sigma = 0.0;              // m, object position
  double orientation_sigma = 0.0;           // rad, object orientation (per axis)
  double angular_velocity_sigma = 0.0;      // rad/s, measured kinematics
  double linear_acceleration_sigma = 0.0;   // m/s^2, measured kinematics
  double angular_acceleration_sigma = 0.0;  // rad/s^2, measured kinematics
};

// The mesh test's default tolerance: a CAD model with one uniform density per
// part (cavities, inserts, coatings) is an idealisation of about 3 % in the
// mass, a principal second moment or the CoM's place within the radius of
// gyration, so smaller disagreements are not called contradictions.
inline constexpr double kDefaultMeshTolerance = 0.03;

// Options of one method each (as ProxSuite and Drake keep settings per
// solver); a method ignores the others'.

// BASELINE_LS: Savitzky-Golay smoothing of the wrench and kinematics.
struct BaselineLsOptions {
  bool savitzky_golay = false;
  int savitzky_golay_window = 51;  // odd, >= 5 (cubic); clipped to the data
};

// CONSTRAINED.
struct ConstrainedOptions {
  // Without a prior: weight of a weak entropic (Bregman) regulariser towards
  // an isotropic guess built from the data (mass and CoM of the
  // unconstrained fit, its mean second moment). In chi^2 units: 1 = "each
  // principal second moment within a factor ~e of the guess" as strong as
  // ONE sample; it only matters in poorly excited directions and keeps them
  // off the boundary of the consistent set. 0 disables.
  double regularization = 1.0;
  // With a mesh and no `prior`: weight of the mesh's uniform-density
  // inertia, scaled to the fitted mass, as the prior (>= 0, chi^2 units like
  // prior.weight).
  double mesh_prior_weight = 1.0;
};

// FACTOR_GRAPH: factor noise (the paper tuned these once on noise-free
// simulation and kept them fixed). Measurement-factor sigmas come from
// InertiaOptions::noise (floored at the values below when 0/unknown).
struct FactorGraphOptions {
  double dynamics_force_sigma = 0.01;   // N
  double dynamics_torque_sigma = 0.01;  // N m
  double min_force_sigma = 0.01;        // N
  double min_torque_sigma = 0.001;      // N m
  double min_position_sigma = 1e-6;     // m
  double min_orientation_sigma = 1e-6;  // rad
  double constraint_sigma = 1e-4;       // relative: active constraint factors
  FactorGraphVariant variant = FactorGraphVariant::kConstraint;
};

// DENSITY.
struct DensityFitOptions {
  RegionOptions regions;
  // Strength of the smoothness regulariser between neighbouring regions
  // (relative units, see README); < 0: chosen by held-out time blocks.
  double regularization = -1.0;
  int folds = 5;  // contiguous time blocks for the held-out choice (>= 2)
  // The mesh test (README, "the mesh test"): the mesh is rejected when
  // every density its regions can carry is farther than this (first-order
  // Riemannian; 0.03 = 3 % of the mass or of a principal second moment, or a
  // CoM move of 3 %/sqrt(2) of the radius of gyration) from the free
  // 10-parameter fit's 99.9 % chi^2 ellipsoid. >= 0; 0 disables the test.
  double mesh_tolerance = kDefaultMeshTolerance;
};

struct InertiaOptions {
  InertiaMethod method = InertiaMethod::kConstrained;
  Vec3 gravity = Vec3(0, 0, -9.81);  // world frame (m/s^2)
  // Convex-hull vertices of the object (object frame, m), e.g. a mesh's
  // vertices. Empty: no CoM constraint. Needs 4 non-coplanar points.
  std::vector<Vec3> hull;
  std::optional<InertiaPrior> prior;
  InertiaNoise noise;

  // Closed mesh of the object (object frame, m) and its name for messages.
  // Needed by DENSITY; CONSTRAINED uses its uniform-density inertia as the
  // prior (constrained.mesh_prior_weight) when no `prior` is given. Other
  // methods ignore it (noted). The mesh's vertices also serve as the hull
  // when `hull` is empty.
  std::shared_ptr<const io::TriangleMesh> mesh;
  std::string mesh_name = "mesh";

  BaselineLsOptions baseline_ls;
  ConstrainedOptions constrained;
  FactorGraphOptions factor_graph;
  DensityFitOptions density;

  // CONSTRAINED and DENSITY (their shared generalised least squares):
  // local-polynomial window (samples, odd) for kinematics from poses or for
  // smoothing noisy measured kinematics, 0 = automatic; GLS re-weighting
  // rounds (>= 1).
  int smoothing_window = 0;
  int reweighting_rounds = 3;

  int max_iterations = 100;  // FACTOR_GRAPH LM / CONSTRAINED Newton iterations
  // Directions whose relative singular value (scaled regressor) is below
  // this are reported as poorly excited.
  double excitation_threshold = 1e-3;

  // Called with the fraction done (0..1) during long fits. May be empty.
  std::function<void(double fraction)> progress;
  // The work limit. Polled in every loop of the fit (validation, kinematics,
  // normal equations, residuals, held-out checks, factor-graph iterations
  // and their linear algebra, DENSITY's region building and solves) about
  // once per couple of thousand samples' work, a few ms at most; returning
  // true ends the fit with absl::Cancelled("interrupted"), on 1,000,000
  // samples within about 0.15 s (README, "Work limit"). May be empty.
  std::function<bool()> interrupt;
};

// Checks the options (InvalidArgument naming the field, e.g. "hull: ...",
// "prior.com ... is outside the hull", "noise.force_sigma: negative",
// "prior: the factor-graph variant fg-c-g needs a prior").
absl::Status ValidateInertiaOptions(const InertiaOptions& options);

struct InertiaFit {
  InertiaMethod method = InertiaMethod::kConstrained;
  InertialParameters params;               // mass, CoM, inertia about the CoM
  Vector10d standard = Vector10d::Zero();  // standard parameters (about the origin)
  Vec3 principal_moments = Vec3::Zero();   // ascending (kg m^2)
  Eigen::Matrix3d principal_axes = Eigen::Matrix3d::Identity();  // columns, right-handed
  bool physically_consistent = false;          // 4x4 pseudo-inertia positive definite
  double pseudo_inertia_min_eigenvalue = 0.0;  // of P scaled to unit mass and size
  bool com_in_hull = true;                     // true when no hull was given
  // A non-negative density inside the mesh produces these parameters
  // (DENSITY, by construction; false for the other methods).
  bool density_realizable = false;

  double residual_rms_force = 0.0;   // N, Newton-Euler residual per component
  double residual_rms_torque = 0.0;  // N m

  // Standard errors (1 sigma) of the reported quantities.
  double mass_se = 0.0;
  Vec3 com_se = Vec3::Zero();
  InertiaTensor inertia_se;
  // Covariance of `standard` (pi about the object origin, ToStandard()
  // order; kg, kg m, kg m^2 squared); zero when unknown. What a plan takes
  // as planner::ParameterUncertainty::covariance unchanged.
  Eigen::Matrix<double, 10, 10> covariance = Eigen::Matrix<double, 10, 10>::Zero();

  // Singular values of the column-scaled, whitened regressor, descending,
  // relative to the largest; directions below options.excitation_threshold
  // are described in `poorly_excited` ("0.71 Ixx - 0.71 Iyy", standard
  // parameters about the origin).
  std::vector<double> singular_values;
  std::vector<std::string> poorly_excited;

  // DENSITY: the fitted density per region, the regions (for plots), the
  // regulariser chosen, the mesh check, and the contradiction test.
  struct RegionDensity {
    std::string label;
    double density = 0.0;         // kg/m^3
    double volume = 0.0;          // m^3
    double standard_error = 0.0;  // kg/m^3 (0 when unknown)
  };
  std::vector<RegionDensity> densities;
  std::shared_ptr<const RegionModel> region_model;
  double density_regularization = 0.0;      // the strength used
  std::string density_regularization_rule;  // "held-out time blocks (5 folds)" or "given"
  std::optional<io::MeshCheck> mesh_check;
  // Held-out weighted residual of DENSITY relative to CONSTRAINED's (0 = not tested).
  double heldout_residual_ratio = 0.0;
  bool mesh_contradicted = false;  // the answer is CONSTRAINED's
  std::string mesh_contradiction;  // one line, empty when not contradicted

  int iterations = 0;
  double time_seconds = 0.0;       // wall clock
  double cpu_seconds = 0.0;        // CPU time of the calling thread (all work runs in it)
  int samples_used = 0;            // samples that produced an equation
  std::vector<std::string> notes;  // e.g. "prior ignored by baseline-ls"
};

// Human-readable multi-line summary (CLI output).
std::string DescribeFit(const InertiaFit& fit);

// About the most memory (bytes) a fit of `samples` samples with `method`
// takes beyond the samples themselves, so a service can refuse a fit it
// cannot hold before starting it. Slopes of peak RSS measured on simulated
// wrist and in-hand data (20k-60k samples, `/usr/bin/time` on `tactforce
// inertia`, rounded up): FACTOR_GRAPH ~4.5 KB per sample (its banded
// system), the others ~2 KB (DENSITY at kMaxTargetRegions regions).
int64_t FitWorkingBytes(InertiaMethod method, int64_t samples);

// Validates samples and options, then fits with options.method.
absl::StatusOr<InertiaFit> FitInertia(const InertiaSamples& samples, const InertiaOptions& options);

// Minimum number of samples a fit with `method` needs: 2 with measured
// kinematics (12 equations for 10 parameters); from poses 4 for
// BASELINE_LS and FACTOR_GRAPH (two three-point differences) and 5 for
// CONSTRAINED (a cubic smoothing fit).
int MinimumSamples(const InertiaSamples& samples, InertiaMethod method);

}  // namespace tactforce::inertia
