// Contact-force estimation from inaccurate tactile readings (GeoDEx
// Problems 1-2, and a normal-only least-squares estimator of ours).
//
// Inputs are the planner's problem (object, contacts, external wrench; all
// in the object frame, SI units) plus one normal-force reading (N) per
// INTRINSIC contact, in request order. Extrinsic contacts have no reading.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "absl/status/statusor.h"
#include "tactforce/planner/types.h"
#include "tactforce/planner/workspace.h"

namespace tactforce::estimator {

using planner::Vec3;

enum class EstimateMethod {
  // GeoDEx: orthogonal projection of the measured force onto the FE-plane
  // (Problem 1); with extrinsic contacts the small QP of Problem 2.
  kProjection,
  // Ours: readings measure only normal components; fit them (weighted by
  // 1/sigma^2) on the FE-plane with a small pull to zero force, subject to
  // every contact inside its pyramidal cone with n . f >= 0.
  kNormalLsq,
};

struct EstimateOptions {
  EstimateMethod method = EstimateMethod::kProjection;
  double origin_weight = 1e-2;  // lambda >= 0
  // The problem is validated and its FE-plane built as the planner does,
  // with these settings: plan.cone_sides (NORMAL_LSQ cone pyramid, 3..64),
  // plan.rank_tolerance and plan.max_contacts (the caller's limit,
  // api::SetLibraryLimits). Its other fields are not used.
  planner::PlanOptions plan;
  // NORMAL_LSQ: sigma below this floor (N) is raised to it (a perfect
  // sensor would otherwise get an infinite weight).
  double min_sigma = 1e-3;
};

enum class EstimateStatus { kOk, kInfeasible, kSolverFailure };
const char* ToString(EstimateStatus status);
const char* ToString(EstimateMethod method);

struct ForceEstimate {
  EstimateStatus status = EstimateStatus::kSolverFailure;
  std::string message;  // also notes flagged readings (e.g. negative values)
  EstimateMethod method = EstimateMethod::kProjection;
  std::vector<Vec3> forces;            // per contact, request order (N)
  std::vector<double> normal_forces;   // n_i . f_i (N)
  std::vector<double> residuals;       // per reading: n_j . f_j - reading_j (N)
  std::vector<int> negative_readings;  // indices (into readings) below zero
  int iterations = 0;
  int64_t solve_time_us = 0;
};

// Errors (InvalidArgument naming the field): anything ValidateProblem
// rejects, "readings: expected N values (one per intrinsic contact), got M",
// "readings[j]: not a finite number", bad options. Negative readings are
// allowed (a miscalibrated sensor can report them) and flagged.
absl::StatusOr<ForceEstimate> EstimateForces(const planner::PlanProblem& problem,
                                             const std::vector<double>& readings,
                                             const EstimateOptions& options = {});

// Buffers of EstimateForces kept between calls, one per thread: the
// planner's workspace (validated problem, FE-plane, rows, QP) and the
// readings' placement. Once warm, a PROJECTION or NORMAL_LSQ estimate of a
// problem of the same sizes allocates nothing (messages aside).
struct EstimationWorkspace {
  planner::PlanningWorkspace planning;
  std::vector<int> intrinsic, extrinsic;  // contact indices
  Eigen::MatrixXd placed;                 // unit normals placed at their contacts' rows (3n x k)
  Eigen::MatrixXd reduced;                // placed^T B or B^T N_E
  Eigen::MatrixXd weighted;               // W (placed^T B)
  Eigen::VectorXd measured, values, coordinates;
};

// The same estimate in place: `out` is overwritten (storage reused) and
// meaningful only when the returned status is OK.
absl::Status EstimateForces(const planner::PlanProblem& problem,
                            const std::vector<double>& readings, const EstimateOptions& options,
                            EstimationWorkspace* workspace, ForceEstimate* out);

}  // namespace tactforce::estimator
