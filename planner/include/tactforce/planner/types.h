// Problem, options and result types of the tactforce force planner.
//
// Units are SI throughout (m, kg, N, N m, s). Every vector is expressed in
// the OBJECT frame. Forces are those a contact applies TO the object.
#pragma once

#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace tactforce::planner {

using Vec3 = Eigen::Vector3d;

enum class ContactKind {
  kIntrinsic,  // tactile fingertip: its normal force is read, with noise sigma
  kExtrinsic,  // environment contact: no reading, no noise
};

struct Contact {
  std::string name;
  Vec3 position = Vec3::Zero();  // contact point (m)
  Vec3 normal = Vec3::UnitZ();   // unit, pointing INTO the object
  double friction = 0.5;         // Coulomb mu >= 0
  // Std. dev. of mu (0 = known): the plan uses the cone at
  // mu - kappa sigma_mu (kappa = PlanOptions::confidence), clipped at 0.
  double friction_sigma = 0.0;
  ContactKind kind = ContactKind::kIntrinsic;
  double sigma = 0.0;             // reading std. dev. (N); ignored if extrinsic
  double min_normal_force = 0.0;  // N
  double max_normal_force = 0.0;  // N; 0 = unbounded
};

// The 10 inertial parameters pi = (m, m c_x, m c_y, m c_z, I_xx, I_yy, I_zz,
// I_xy, I_xz, I_yz), inertia about the OBJECT ORIGIN (kg, kg m, kg m^2).
using Matrix10d = Eigen::Matrix<double, 10, 10>;

// Uncertainty of pi the plan must hold against (parameter_uncertainty.h):
// every pi in the ellipsoid {dpi^T covariance^+ dpi <= kappa_b^2}.
struct ParameterUncertainty {
  Matrix10d covariance = Matrix10d::Zero();  // of pi; zero = known
  std::optional<double> confidence;          // kappa_b; empty: PlanOptions::confidence
};

struct ObjectModel {
  double mass = 0.0;                 // kg
  Vec3 com = Vec3::Zero();           // m
  Vec3 gravity = Vec3(0, 0, -9.81);  // m/s^2
  ParameterUncertainty uncertainty;
};

// The object's motion at the planned instant (object frame), for the wrench
// regressor b = Y pi; zero = static. The wrench itself is carried by
// `external_wrench` (StepProblem), so a plan without uncertainty ignores it.
struct Motion {
  Vec3 linear_acceleration = Vec3::Zero();   // of the origin (m/s^2)
  Vec3 angular_velocity = Vec3::Zero();      // rad/s
  Vec3 angular_acceleration = Vec3::Zero();  // rad/s^2
};

// Force (N) and torque about the object origin (N m).
struct Wrench {
  Vec3 force = Vec3::Zero();
  Vec3 torque = Vec3::Zero();
};

// What must be balanced and by which contacts.
struct PlanProblem {
  ObjectModel object;
  std::vector<Contact> contacts;
  Wrench external_wrench;  // also balanced by the contacts
  Motion motion;
};

enum class ConeModel { kPyramid, kExact };
enum class SolverKind { kGeometric, kIpopt, kCrossCheck };

// Settings of the IPOPT backend (and of CROSS_CHECK's reference solve),
// kept apart from the geometric ones as Drake keeps options per solver.
struct IpoptOptions {
  double tolerance = 1e-9;       // Ipopt's tol (scaled overall NLP error)
  int max_iterations = 3000;     // per Ipopt run
  double max_cpu_seconds = 0.0;  // CPU budget of one solve; 0 = no limit
};

// Settings of a plan (Ceres-style: IsValid explains itself). The member
// initialisers are THE defaults: front ends (the API's unset fields, the
// CLI) take them from PlanOptions{} rather than repeating them. The state
// of one call (its interrupt) is not a setting: SolveControl (below).
struct PlanOptions {
  static constexpr int kMinConeSides = 3;
  static constexpr int kMaxConeSides = 64;
  // kappa is a number of standard deviations; beyond this it only overflows.
  static constexpr double kMaxConfidence = 1e3;

  ConeModel cone = ConeModel::kPyramid;
  int cone_sides = 12;           // k, facets of the inscribed pyramid, kMin..kMaxConeSides
  double confidence = 1.0;       // kappa >= 0: rows tightened by kappa * ellipsoid support
  double rank_tolerance = 1e-9;  // relative singular-value cut-off for null(G)
  int max_contacts = 64;         // a limit of the caller (api::CallLimits), checked by validation

  // Geometric backend: constraint rows active at a previous, similar solve
  // (PlanResult::geometric.active_set). Only speeds things up; never changes the answer.
  std::vector<int> warm_start;

  IpoptOptions ipopt;  // the Ipopt reference

  // Cross-check agreement threshold on forces (N).
  double agreement_tolerance = 1e-5;

  bool IsValid(std::string* error) const;
};

// The state of one solve, apart from its options (which describe the
// problem): what the caller can stop it with.
struct SolveControl {
  // Polled between iterations by iterative backends (Ipopt) and between the
  // steps of a motion; returning true stops the solve with kSolverFailure
  // and a message starting "interrupted". RPC deadlines and cancellation.
  // May be empty.
  std::function<bool()> interrupt;
};

enum class PlanStatus { kOptimal, kInfeasible, kSolverFailure };

// What made a plan infeasible when uncertainty is present: the plan is
// feasible once that source's tightening alone is removed (kNominal:
// infeasible even without any; kCombined: only removing several helps).
enum class UncertaintySource { kNone, kNominal, kMeasurement, kParameters, kFriction, kCombined };
const char* ToString(UncertaintySource source);

// One tightened constraint's margin split by source (N), at the plan.
struct RowMargin {
  int contact = 0;
  bool cone = false;         // EXACT cone of `contact` rather than a row
  int row = -1;              // index into the prepared rows (-1 for a cone)
  int facet = -1;            // a pyramid facet's index; -1: a normal-force bound or a cone
  bool upper = false;        // the maximum (not minimum) normal-force bound
  double slack = 0.0;        // of the tightened row / cone at the forces
  double measurement = 0.0;  // kappa sqrt(a^T S_f a) (cone: kappa (mu rho_n + rho_t))
  double parameters = 0.0;   // kappa_b sqrt(a^T G^+ S_b G^+T a) (cone: likewise)
};

const char* ToString(PlanStatus status);
const char* ToString(SolverKind solver);

struct CrossCheckReport {
  bool agree = false;
  double max_force_diff = 0.0;      // N
  double objective_rel_diff = 0.0;  // |J_g - J_i| / max(1, |J_i|)
  int64_t geometric_time_us = 0;
  int64_t ipopt_time_us = 0;
  PlanStatus ipopt_status = PlanStatus::kSolverFailure;
  std::string ipopt_message;
};

// What the IPOPT backend reports beyond the common result (after Drake's
// IpoptSolverDetails): Ipopt's own return status of the last run and how
// many runs the solve took (1: the minimum-norm problem; 3: phase one and
// a retry from its feasible point). Empty (runs 0) for other backends and
// for answers decided without Ipopt (e.g. a wrench G cannot resist).
struct IpoptDetails {
  int runs = 0;
  int status = 0;           // Ipopt::ApplicationReturnStatus of the last run
  std::string status_name;  // its name ("Solve_Succeeded")
};

// What the GEOMETRIC backend reports beyond the common result (beside
// IpoptDetails): the constraint rows active at its optimum, which warm-start
// a similar next solve (PlanOptions::warm_start). Empty for other backends.
struct GeometricDetails {
  std::vector<int> active_set;
};

// Relative size below which a margin is round-off (see PlanResult::min_margin).
inline constexpr double kMarginRoundOff = 1e-9;

// The answer. Infeasibility is a result, not an error.
struct PlanResult {
  PlanStatus status = PlanStatus::kSolverFailure;
  std::string message;
  std::vector<Vec3> forces;                // per contact, request order (N)
  std::vector<double> normal_forces;       // n_i . f_i (N)
  std::vector<double> normal_force_sigma;  // rho_n,i (N)
  double objective = 0.0;                  // sum |f_i|^2 (N^2)
  // Smallest slack of the tightened rows (N); exactly 0 when within round-off
  // (|margin| <= kMarginRoundOff x max(1 N, largest force component)).
  double min_margin = 0.0;
  SolverKind solver = SolverKind::kGeometric;
  int64_t solve_time_us = 0;
  int iterations = 0;
  std::optional<CrossCheckReport> cross_check;
  // IPOPT (and CROSS_CHECK's reference solve, inside cross_check's report
  // fields): Ipopt's own status.
  IpoptDetails ipopt;
  GeometricDetails geometric;  // GEOMETRIC (and CROSS_CHECK's answer)
  // Only when the problem carries uncertainty (object.uncertainty or a
  // friction_sigma); empty otherwise, so such plans are unchanged.
  std::vector<RowMargin> row_margins;  // every row, then every EXACT cone
  UncertaintySource infeasible_source = UncertaintySource::kNone;
};

}  // namespace tactforce::planner
