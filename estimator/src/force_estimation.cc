// Force estimation from tactile readings (force_estimation.h): GeoDEx's
// projection onto the force-equilibrium plane (Problem 1, and Problem 2 with
// extrinsic contacts as a QP) and NORMAL_LSQ, which fits only the sensed
// normal components inside the friction cones; both with the planner's
// dense QP.
#include "tactforce/estimator/force_estimation.h"

#include <chrono>
#include <cmath>

#include "absl/strings/str_cat.h"
#include "tactforce/planner/dense_qp.h"
#include "tactforce/planner/force_model.h"
#include "tactforce/planner/validation.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::estimator {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using planner::ContactKind;
using planner::DenseQp;
using planner::DenseQpStatus;
using planner::ForceEquilibrium;
using planner::PlanProblem;

void Classify(const PlanProblem& p, EstimationWorkspace* ws) {
  ws->intrinsic.clear();
  ws->extrinsic.clear();
  for (int i = 0; i < static_cast<int>(p.contacts.size()); ++i) {
    (p.contacts[i].kind == ContactKind::kIntrinsic ? ws->intrinsic : ws->extrinsic).push_back(i);
  }
}

// Columns: unit normals placed at their contacts' rows (3n x |indices|).
void PlaceNormals(const PlanProblem& p, const std::vector<int>& indices, MatrixXd* out) {
  out->setZero(3 * p.contacts.size(), indices.size());
  for (size_t j = 0; j < indices.size(); ++j) {
    out->block<3, 1>(3 * indices[j], j) = p.contacts[indices[j]].normal;
  }
}

const char* QpFailure(DenseQpStatus s) {
  return s == DenseQpStatus::kIterationLimit ? "active-set iteration limit reached"
                                             : "numerical failure in the active-set QP";
}

// f = f0 + B x into planning.forces.
void ForcesFromPlane(const ForceEquilibrium& eq, const VectorXd& x, planner::PlanningWorkspace* w) {
  w->forces = eq.particular;
  w->forces.noalias() += eq.null_basis * x;
}

// GeoDEx Problem 1 (closed form) and Problem 2 (QP over x and w >= 0).
void Project(const PlanProblem& p, const std::vector<double>& readings, double lambda,
             EstimationWorkspace* ws, ForceEstimate* out) {
  planner::PlanningWorkspace& pw = ws->planning;
  const ForceEquilibrium& eq = pw.prepared.equilibrium;
  const MatrixXd& B = eq.null_basis;
  PlaceNormals(p, ws->intrinsic, &ws->placed);
  ws->measured.noalias() =
      ws->placed * Eigen::Map<const VectorXd>(readings.data(), readings.size());
  ws->measured -= eq.particular;  // r = f_m - f0
  if (ws->extrinsic.empty()) {
    ws->coordinates.noalias() = B.transpose() * ws->measured;
    ForcesFromPlane(eq, ws->coordinates, &pw);
    out->status = EstimateStatus::kOk;
    return;
  }
  // minimise |f0 + Bx - f_m - N_E w|^2 + lambda |f0 + Bx|^2,  w >= 0.
  // With B^T B = I and B^T f0 = 0 the Hessian (times 1/2) is
  // [(1+lambda) I, -B^T N_E; -N_E^T B, N_E^T N_E], strictly convex for lambda > 0.
  const int d = static_cast<int>(B.cols());
  const int e = static_cast<int>(ws->extrinsic.size());
  PlaceNormals(p, ws->extrinsic, &ws->placed);         // now N_E
  ws->reduced.noalias() = B.transpose() * ws->placed;  // B^T N_E
  DenseQp& qp = pw.qp;
  qp.identity_hessian = false;
  qp.hessian.resize(d + e, d + e);
  qp.hessian.topLeftCorner(d, d).setIdentity();
  qp.hessian.topLeftCorner(d, d) *= 2.0 * (1.0 + lambda);
  qp.hessian.topRightCorner(d, e) = -2.0 * ws->reduced;
  qp.hessian.bottomLeftCorner(e, d) = -2.0 * ws->reduced.transpose();
  qp.hessian.bottomRightCorner(e, e).noalias() = 2.0 * ws->placed.transpose() * ws->placed;
  // r = f0 - f_m = -measured.
  qp.gradient.resize(d + e);
  qp.gradient.head(d).noalias() = -2.0 * B.transpose() * ws->measured;
  qp.gradient.head(d).noalias() += (2.0 * lambda) * B.transpose() * eq.particular;
  qp.gradient.tail(e).noalias() = 2.0 * ws->placed.transpose() * ws->measured;
  qp.eq_matrix.resize(0, d + e);
  qp.eq_rhs.resize(0);
  qp.in_matrix.setZero(e, d + e);
  qp.in_matrix.rightCols(e).diagonal().setConstant(-1.0);
  qp.in_rhs.setZero(e);
  planner::SolveDenseQp(qp, {}, &pw.qp_workspace, &pw.qp_result);
  out->iterations = pw.qp_result.iterations;
  if (pw.qp_result.status != DenseQpStatus::kOptimal) {
    out->status = EstimateStatus::kSolverFailure;
    out->message = QpFailure(pw.qp_result.status);
    return;
  }
  ws->coordinates = pw.qp_result.x.head(d);
  ForcesFromPlane(eq, ws->coordinates, &pw);
  out->status = EstimateStatus::kOk;
}

void NormalLeastSquares(PlanProblem& p, const std::vector<double>& readings,
                        const EstimateOptions& o, EstimationWorkspace* ws, ForceEstimate* out) {
  planner::PlanningWorkspace& pw = ws->planning;
  const ForceEquilibrium& eq = pw.prepared.equilibrium;
  const MatrixXd& B = eq.null_basis;
  const int d = static_cast<int>(B.cols());
  const int k = static_cast<int>(ws->intrinsic.size());
  // M = placed^T: f -> the intrinsic normal components; W = diag(1 / sigma^2).
  PlaceNormals(p, ws->intrinsic, &ws->placed);
  ws->reduced.noalias() = ws->placed.transpose() * B;             // M B
  ws->measured.resize(k);                                         // here: the weights
  ws->values.noalias() = ws->placed.transpose() * eq.particular;  // M f0 - y
  for (int j = 0; j < k; ++j) {
    const double s = std::max(p.contacts[ws->intrinsic[j]].sigma, o.min_sigma);
    ws->measured(j) = 1.0 / (s * s);
    ws->values(j) = ws->measured(j) * (ws->values(j) - readings[j]);
  }
  ws->weighted.noalias() = ws->measured.asDiagonal() * ws->reduced;
  DenseQp& qp = pw.qp;
  qp.identity_hessian = false;
  qp.hessian.noalias() = ws->reduced.transpose() * ws->weighted;
  qp.hessian.diagonal().array() += o.origin_weight;
  qp.hessian *= 2.0;
  qp.gradient.noalias() = ws->reduced.transpose() * ws->values;
  qp.gradient.noalias() += o.origin_weight * B.transpose() * eq.particular;
  qp.gradient *= 2.0;
  qp.eq_matrix.resize(0, d);
  qp.eq_rhs.resize(0);
  // Untightened pyramid and n . f >= 0 for every contact (the workspace's
  // copy of the problem loses its force bounds; the rows see no noise).
  for (auto& c : p.contacts) c.min_normal_force = c.max_normal_force = 0.0;
  planner::MeasurementEllipsoid& no_noise = pw.prepared.ellipsoid;
  no_noise.factor.resize(3 * p.contacts.size(), 0);
  planner::ConstraintRows& rows = pw.prepared.rows;
  planner::BuildConstraintRows(p, no_noise, o.plan.cone_sides, 0.0, true, &rows);
  planner::RowsOnPlane(rows, eq, &qp.in_matrix, &qp.in_rhs);
  planner::SolveDenseQp(qp, {}, &pw.qp_workspace, &pw.qp_result);
  const planner::DenseQpResult& qr = pw.qp_result;
  out->iterations = qr.iterations;
  switch (qr.status) {
    case DenseQpStatus::kOptimal:
      ForcesFromPlane(eq, qr.x, &pw);
      out->status = EstimateStatus::kOk;
      return;
    case DenseQpStatus::kInfeasible:
      out->status = EstimateStatus::kInfeasible;
      out->message = absl::StrCat("no equilibrium force keeps every contact in its cone: ",
                                  rows.Describe(qr.blocking_row, p));
      return;
    default:
      out->status = EstimateStatus::kSolverFailure;
      out->message = qr.status == DenseQpStatus::kNumericalError && o.origin_weight == 0.0
                         ? "origin_weight 0 needs readings that determine every force"
                         : QpFailure(qr.status);
  }
}

}  // namespace

const char* ToString(EstimateStatus status) {
  switch (status) {
    case EstimateStatus::kOk:
      return "OK";
    case EstimateStatus::kInfeasible:
      return "INFEASIBLE";
    case EstimateStatus::kSolverFailure:
      return "SOLVER_FAILURE";
  }
  return "UNKNOWN";
}

const char* ToString(EstimateMethod method) {
  return method == EstimateMethod::kProjection ? "PROJECTION" : "NORMAL_LSQ";
}

namespace {

// Validates into the workspace and checks the readings; fills
// out->negative_readings.
absl::Status CheckRequest(const PlanProblem& problem, const std::vector<double>& readings,
                          const EstimateOptions& options, EstimationWorkspace* ws,
                          ForceEstimate* out) {
  if (!std::isfinite(options.origin_weight) || options.origin_weight < 0.0)
    return absl::InvalidArgumentError("origin_weight: must be finite and >= 0");
  PlanProblem& p = ws->planning.prepared.problem;
  TF_RETURN_IF_ERROR(planner::ValidateProblem(problem, options.plan, &p));
  Classify(p, ws);
  if (readings.size() != ws->intrinsic.size()) {
    return absl::InvalidArgumentError(absl::StrCat(
        "readings: expected ", ws->intrinsic.size(),
        " values (one per intrinsic contact, in request order), got ", readings.size()));
  }
  for (size_t j = 0; j < readings.size(); ++j) {
    if (!planner::IsBounded(readings[j], planner::kMaxForce))
      return planner::MagnitudeError(absl::StrCat("readings[", j, "]"), readings[j],
                                     planner::kMaxForce, "N");
    if (readings[j] < 0.0) out->negative_readings.push_back(static_cast<int>(j));
  }
  if (options.method == EstimateMethod::kProjection && !ws->extrinsic.empty() &&
      options.origin_weight <= 0.0) {
    return absl::InvalidArgumentError(
        "origin_weight: must be > 0 for PROJECTION with extrinsic contacts (Problem 2)");
  }
  return absl::OkStatus();
}

void Reset(ForceEstimate* out, EstimateMethod method) {
  out->status = EstimateStatus::kSolverFailure;
  out->message.clear();
  out->method = method;
  out->forces.clear();
  out->normal_forces.clear();
  out->residuals.clear();
  out->negative_readings.clear();
  out->iterations = 0;
  out->solve_time_us = 0;
}

}  // namespace

absl::Status EstimateForces(const PlanProblem& problem, const std::vector<double>& readings,
                            const EstimateOptions& options, EstimationWorkspace* ws,
                            ForceEstimate* out) {
  const auto start = std::chrono::steady_clock::now();
  Reset(out, options.method);
  TF_RETURN_IF_ERROR(CheckRequest(problem, readings, options, ws, out));
  PlanProblem& p = ws->planning.prepared.problem;
  ForceEquilibrium& eq = ws->planning.prepared.equilibrium;
  planner::ComputeForceEquilibrium(p, options.plan.rank_tolerance,
                                   &ws->planning.equilibrium_scratch, &eq);
  if (!eq.consistent) {
    out->status = EstimateStatus::kInfeasible;
    out->message = absl::StrCat("the contacts cannot resist this wrench: G has rank ", eq.rank,
                                " and the required wrench leaves a residual of ", eq.residual);
  } else if (options.method == EstimateMethod::kProjection) {
    Project(p, readings, options.origin_weight, ws, out);
  } else {
    NormalLeastSquares(p, readings, options, ws, out);
  }
  if (out->status == EstimateStatus::kOk) {
    const VectorXd& f = ws->planning.forces;
    out->forces.resize(p.contacts.size());
    out->normal_forces.resize(p.contacts.size());
    for (size_t i = 0; i < p.contacts.size(); ++i) {
      out->forces[i] = f.segment<3>(3 * i);
      out->normal_forces[i] = p.contacts[i].normal.dot(out->forces[i]);
    }
    out->residuals.resize(ws->intrinsic.size());
    for (size_t j = 0; j < ws->intrinsic.size(); ++j) {
      out->residuals[j] = out->normal_forces[ws->intrinsic[j]] - readings[j];
    }
  }
  if (!out->negative_readings.empty()) {
    absl::StrAppend(&out->message, out->message.empty() ? "" : "; ", out->negative_readings.size(),
                    " negative reading(s) used as given (first: readings[",
                    out->negative_readings.front(), "])");
  }
  out->solve_time_us = std::chrono::duration_cast<std::chrono::microseconds>(
                           std::chrono::steady_clock::now() - start)
                           .count();
  return absl::OkStatus();
}

absl::StatusOr<ForceEstimate> EstimateForces(const PlanProblem& problem,
                                             const std::vector<double>& readings,
                                             const EstimateOptions& options) {
  EstimationWorkspace workspace;
  ForceEstimate out;
  TF_RETURN_IF_ERROR(EstimateForces(problem, readings, options, &workspace, &out));
  return out;
}

}  // namespace tactforce::estimator
