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

namespace tactforce::estimator {
namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;
using planner::ContactKind;
using planner::DenseQp;
using planner::DenseQpStatus;
using planner::ForceEquilibrium;
using planner::PlanProblem;

struct Layout {
  std::vector<int> intrinsic, extrinsic;  // contact indices
};

Layout Classify(const PlanProblem& p) {
  Layout l;
  for (int i = 0; i < static_cast<int>(p.contacts.size()); ++i) {
    (p.contacts[i].kind == ContactKind::kIntrinsic ? l.intrinsic : l.extrinsic).push_back(i);
  }
  return l;
}

// Columns: unit normals placed at their contacts' rows (3n x |indices|).
MatrixXd PlacedNormals(const PlanProblem& p, const std::vector<int>& indices) {
  MatrixXd out = MatrixXd::Zero(3 * p.contacts.size(), indices.size());
  for (size_t j = 0; j < indices.size(); ++j) {
    out.block<3, 1>(3 * indices[j], j) = p.contacts[indices[j]].normal;
  }
  return out;
}

const char* QpFailure(DenseQpStatus s) {
  return s == DenseQpStatus::kIterationLimit ? "active-set iteration limit reached"
                                             : "numerical failure in the active-set QP";
}

// GeoDEx Problem 1 (closed form) and Problem 2 (QP over x and w >= 0).
void Project(const PlanProblem& p, const ForceEquilibrium& eq, const Layout& l,
             const VectorXd& measured, double lambda, ForceEstimate* out, VectorXd* f) {
  const MatrixXd& B = eq.null_basis;
  if (l.extrinsic.empty()) {
    *f = eq.particular + B * (B.transpose() * (measured - eq.particular));
    out->status = EstimateStatus::kOk;
    return;
  }
  // minimise |f0 + Bx - f_m - N_E w|^2 + lambda |f0 + Bx|^2,  w >= 0.
  // With B^T B = I and B^T f0 = 0 the Hessian (times 1/2) is
  // [(1+lambda) I, -B^T N_E; -N_E^T B, N_E^T N_E], strictly convex for lambda > 0.
  const int d = static_cast<int>(B.cols());
  const int e = static_cast<int>(l.extrinsic.size());
  const MatrixXd n_e = PlacedNormals(p, l.extrinsic);
  const VectorXd r = eq.particular - measured;
  DenseQp qp;
  qp.hessian.resize(d + e, d + e);
  qp.hessian << (1.0 + lambda) * MatrixXd::Identity(d, d), -B.transpose() * n_e,
      -n_e.transpose() * B, n_e.transpose() * n_e;
  qp.hessian *= 2.0;
  qp.gradient.resize(d + e);
  qp.gradient << 2.0 * (B.transpose() * r + lambda * B.transpose() * eq.particular),
      -2.0 * n_e.transpose() * r;
  qp.eq_matrix.resize(0, d + e);
  qp.eq_rhs.resize(0);
  qp.in_matrix = MatrixXd::Zero(e, d + e);
  qp.in_matrix.rightCols(e) = -MatrixXd::Identity(e, e);
  qp.in_rhs = VectorXd::Zero(e);
  const planner::DenseQpResult qr = planner::SolveDenseQp(qp);
  out->iterations = qr.iterations;
  if (qr.status != DenseQpStatus::kOptimal) {
    out->status = EstimateStatus::kSolverFailure;
    out->message = QpFailure(qr.status);
    return;
  }
  *f = eq.particular + B * qr.x.head(d);
  out->status = EstimateStatus::kOk;
}

void NormalLeastSquares(const PlanProblem& p, const ForceEquilibrium& eq, const Layout& l,
                        const std::vector<double>& readings, const EstimateOptions& o,
                        ForceEstimate* out, VectorXd* f) {
  const MatrixXd& B = eq.null_basis;
  const int d = static_cast<int>(B.cols());
  // M f = the intrinsic normal components; W = diag(1 / sigma^2).
  const MatrixXd m = PlacedNormals(p, l.intrinsic).transpose();
  VectorXd w(l.intrinsic.size()), y(l.intrinsic.size());
  for (size_t j = 0; j < l.intrinsic.size(); ++j) {
    const double s = std::max(p.contacts[l.intrinsic[j]].sigma, o.min_sigma);
    w(j) = 1.0 / (s * s);
    y(j) = readings[j];
  }
  const MatrixXd mb = m * B;
  DenseQp qp;
  qp.hessian = 2.0 * (mb.transpose() * w.asDiagonal() * mb +
                      o.origin_weight * MatrixXd::Identity(d, d));
  qp.gradient = 2.0 * (mb.transpose() * w.asDiagonal() * (m * eq.particular - y) +
                       o.origin_weight * B.transpose() * eq.particular);
  qp.eq_matrix.resize(0, d);
  qp.eq_rhs.resize(0);
  // Untightened pyramid and n . f >= 0 for every contact.
  PlanProblem admissible = p;
  for (auto& c : admissible.contacts) c.min_normal_force = c.max_normal_force = 0.0;
  const planner::MeasurementEllipsoid no_noise{MatrixXd::Zero(3 * p.contacts.size(), 0)};
  const planner::ConstraintRows rows =
      planner::BuildConstraintRows(admissible, no_noise, o.cone_sides, 0.0, true);
  qp.in_matrix = rows.matrix * B;
  qp.in_rhs = rows.rhs - rows.matrix * eq.particular;
  const planner::DenseQpResult qr = planner::SolveDenseQp(qp);
  out->iterations = qr.iterations;
  switch (qr.status) {
    case DenseQpStatus::kOptimal:
      *f = eq.particular + B * qr.x;
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
    case EstimateStatus::kOk: return "OK";
    case EstimateStatus::kInfeasible: return "INFEASIBLE";
    case EstimateStatus::kSolverFailure: return "SOLVER_FAILURE";
  }
  return "UNKNOWN";
}

const char* ToString(EstimateMethod method) {
  return method == EstimateMethod::kProjection ? "PROJECTION" : "NORMAL_LSQ";
}

absl::StatusOr<ForceEstimate> EstimateForces(const PlanProblem& problem,
                                             const std::vector<double>& readings,
                                             const EstimateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!std::isfinite(options.origin_weight) || options.origin_weight < 0.0)
    return absl::InvalidArgumentError("origin_weight: must be finite and >= 0");
  planner::PlanOptions plan_options;
  plan_options.cone_sides = options.cone_sides;
  plan_options.rank_tolerance = options.rank_tolerance;
  plan_options.max_contacts = options.max_contacts;
  absl::StatusOr<PlanProblem> validated = planner::ValidateProblem(problem, plan_options);
  if (!validated.ok()) return validated.status();
  const PlanProblem& p = *validated;
  const Layout layout = Classify(p);
  if (readings.size() != layout.intrinsic.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("readings: expected ", layout.intrinsic.size(),
                     " values (one per intrinsic contact, in request order), got ",
                     readings.size()));
  }
  ForceEstimate out;
  out.method = options.method;
  for (size_t j = 0; j < readings.size(); ++j) {
    if (!std::isfinite(readings[j]))
      return absl::InvalidArgumentError(absl::StrCat("readings[", j, "]: not a finite number"));
    if (readings[j] < 0.0) out.negative_readings.push_back(static_cast<int>(j));
  }
  if (options.method == EstimateMethod::kProjection && !layout.extrinsic.empty() &&
      options.origin_weight <= 0.0) {
    return absl::InvalidArgumentError(
        "origin_weight: must be > 0 for PROJECTION with extrinsic contacts (Problem 2)");
  }

  const ForceEquilibrium eq = planner::ComputeForceEquilibrium(p, options.rank_tolerance);
  VectorXd f;
  if (!eq.consistent) {
    out.status = EstimateStatus::kInfeasible;
    out.message = absl::StrCat("the contacts cannot resist this wrench: G has rank ", eq.rank,
                               " and the required wrench leaves a residual of ", eq.residual);
  } else if (options.method == EstimateMethod::kProjection) {
    VectorXd measured = PlacedNormals(p, layout.intrinsic) *
                        Eigen::Map<const VectorXd>(readings.data(), readings.size());
    Project(p, eq, layout, measured, options.origin_weight, &out, &f);
  } else {
    NormalLeastSquares(p, eq, layout, readings, options, &out, &f);
  }
  if (out.status == EstimateStatus::kOk) {
    for (size_t i = 0; i < p.contacts.size(); ++i) {
      out.forces.push_back(f.segment<3>(3 * i));
      out.normal_forces.push_back(p.contacts[i].normal.dot(out.forces.back()));
    }
    for (size_t j = 0; j < layout.intrinsic.size(); ++j) {
      out.residuals.push_back(out.normal_forces[layout.intrinsic[j]] - readings[j]);
    }
  }
  if (!out.negative_readings.empty()) {
    absl::StrAppend(&out.message, out.message.empty() ? "" : "; ", out.negative_readings.size(),
                    " negative reading(s) used as given (first: readings[",
                    out.negative_readings.front(), "])");
  }
  out.solve_time_us = std::chrono::duration_cast<std::chrono::microseconds>(
                          std::chrono::steady_clock::now() - start)
                          .count();
  return out;
}

}  // namespace tactforce::estimator
