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
  ContactKind kind = ContactKind::kIntrinsic;
  double sigma = 0.0;             // reading std. dev. (N); ignored if extrinsic
  double min_normal_force = 0.0;  // N
  double max_normal_force = 0.0;  // N; 0 = unbounded
};

struct ObjectModel {
  double mass = 0.0;                 // kg
  Vec3 com = Vec3::Zero();           // m
  Vec3 gravity = Vec3(0, 0, -9.81);  // m/s^2
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
};

enum class ConeModel { kPyramid, kExact };
enum class SolverKind { kGeometric, kIpopt, kCrossCheck };

// Settings shared by every backend (Ceres-style: IsValid explains itself).
// The member initialisers are THE defaults: front ends (the API's unset
// fields, the CLI) take them from PlanOptions{} rather than repeating them.
struct PlanOptions {
  static constexpr int kMinConeSides = 3;
  static constexpr int kMaxConeSides = 64;
  // kappa is a number of standard deviations; beyond this it only overflows.
  static constexpr double kMaxConfidence = 1e3;

  ConeModel cone = ConeModel::kPyramid;
  int cone_sides = 12;       // k, facets of the inscribed pyramid, kMin..kMaxConeSides
  double confidence = 1.0;   // kappa >= 0: rows tightened by kappa * ellipsoid support
  double rank_tolerance = 1e-9;  // relative singular-value cut-off for null(G)
  int max_contacts = 64;

  // Ipopt reference.
  double ipopt_tolerance = 1e-9;
  int ipopt_max_iterations = 3000;
  double ipopt_max_cpu_seconds = 0.0;  // 0 = no limit

  // Cross-check agreement threshold on forces (N).
  double agreement_tolerance = 1e-5;

  // Geometric backend: constraint rows active at a previous, similar solve
  // (PlanResult::active_set). Only speeds things up; never changes the answer.
  std::vector<int> warm_start;

  // Polled between iterations by iterative backends (Ipopt); returning true
  // stops the solve with kSolverFailure and a message starting
  // "interrupted". Used for RPC deadlines and cancellation. May be empty.
  std::function<bool()> interrupt;

  bool IsValid(std::string* error) const;
};

enum class PlanStatus { kOptimal, kInfeasible, kSolverFailure };

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
  // Geometric backend: active constraint rows at the optimum (warm starts).
  std::vector<int> active_set;
};

}  // namespace tactforce::planner
