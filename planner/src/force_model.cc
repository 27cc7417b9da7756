// The shared geometry of force_model.h: G and b, the FE-plane, the measurement
// ellipsoid, the tightened rows and cones, and Prepare().
#include "tactforce/planner/force_model.h"

#include <algorithm>
#include <cmath>
#include <numbers>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>

#include "absl/strings/str_cat.h"

namespace tactforce::planner {
namespace {

Eigen::Matrix3d Skew(const Vec3& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

}  // namespace

ForceEquilibrium ComputeForceEquilibrium(const PlanProblem& problem,
                                         double rank_tolerance) {
  const int n = static_cast<int>(problem.contacts.size());
  ForceEquilibrium eq;
  eq.grasp_matrix.setZero(6, 3 * n);
  for (int i = 0; i < n; ++i) {
    eq.grasp_matrix.block<3, 3>(0, 3 * i).setIdentity();
    eq.grasp_matrix.block<3, 3>(3, 3 * i) = Skew(problem.contacts[i].position);
  }
  const ObjectModel& o = problem.object;
  const Vec3 weight = o.mass * o.gravity;
  eq.wrench.head<3>() = -(weight + problem.external_wrench.force);
  eq.wrench.tail<3>() = -(o.com.cross(weight) + problem.external_wrench.torque);

  Eigen::JacobiSVD<MatrixXd> svd(eq.grasp_matrix, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const VectorXd& s = svd.singularValues();
  const double cutoff = rank_tolerance * std::max(1.0, s(0));
  int rank = 0;
  while (rank < s.size() && s(rank) > cutoff) ++rank;
  eq.rank = rank;

  const MatrixXd& U = svd.matrixU();
  const MatrixXd& V = svd.matrixV();
  eq.null_basis = V.rightCols(3 * n - rank);
  const VectorXd projected = U.leftCols(rank).transpose() * eq.wrench;  // U_r^T b
  eq.particular = V.leftCols(rank) * (projected.array() / s.head(rank).array()).matrix();
  eq.residual = (eq.grasp_matrix * eq.particular - eq.wrench).norm();
  eq.consistent = eq.residual <= 1e-8 * std::max(1.0, eq.wrench.norm());
  eq.independent_rows = s.head(rank).asDiagonal() * V.leftCols(rank).transpose();
  eq.independent_rhs = projected;
  return eq;
}

double MeasurementEllipsoid::Support(const VectorXd& a) const {
  return factor.cols() == 0 ? 0.0 : (factor.transpose() * a).norm();
}

Eigen::Matrix3d MeasurementEllipsoid::ContactCovariance(int contact) const {
  if (factor.cols() == 0) return Eigen::Matrix3d::Zero();
  const auto block = factor.middleRows<3>(3 * contact);
  return block * block.transpose();
}

MeasurementEllipsoid ComputeMeasurementEllipsoid(const PlanProblem& problem,
                                                 const ForceEquilibrium& eq) {
  const int n = static_cast<int>(problem.contacts.size());
  // N_I diag(sigma): one column per intrinsic contact with sigma > 0.
  std::vector<int> noisy;
  for (int i = 0; i < n; ++i) {
    const Contact& c = problem.contacts[i];
    if (c.kind == ContactKind::kIntrinsic && c.sigma > 0.0) noisy.push_back(i);
  }
  MeasurementEllipsoid ellipsoid;
  if (noisy.empty() || eq.null_basis.cols() == 0) {
    ellipsoid.factor.setZero(3 * n, 0);
    return ellipsoid;
  }
  MatrixXd scaled_normals = MatrixXd::Zero(3 * n, static_cast<int>(noisy.size()));
  for (int j = 0; j < static_cast<int>(noisy.size()); ++j) {
    const Contact& c = problem.contacts[noisy[j]];
    scaled_normals.block<3, 1>(3 * noisy[j], j) = c.sigma * c.normal;
  }
  // L = B (B^T N_I diag(sigma)): the FE-plane projection of the reading noise.
  ellipsoid.factor = eq.null_basis * (eq.null_basis.transpose() * scaled_normals);
  return ellipsoid;
}

std::pair<Vec3, Vec3> TangentBasis(const Vec3& normal) {
  int axis = 0;
  for (int k = 1; k < 3; ++k) {
    if (std::abs(normal(k)) < std::abs(normal(axis))) axis = k;
  }
  const Vec3 e = Vec3::Unit(axis);
  const Vec3 t1 = (e - e.dot(normal) * normal).normalized();
  return {t1, normal.cross(t1)};
}

std::string ContactLabel(const PlanProblem& problem, int contact) {
  std::string label = absl::StrCat("contact ", contact);
  const std::string& name = problem.contacts[contact].name;
  if (!name.empty()) absl::StrAppend(&label, " (", name, ")");
  return label;
}

std::string ConstraintRows::Describe(int row, const PlanProblem& problem) const {
  if (row < 0 || row >= static_cast<int>(info.size())) return absl::StrCat("row ", row);
  const RowInfo& r = info[row];
  const std::string who = ContactLabel(problem, r.contact);
  switch (r.kind) {
    case RowKind::kFrictionFacet:
      return absl::StrCat(who, " friction cone facet ", r.facet);
    case RowKind::kMinNormal:
      return absl::StrCat(who, " minimum normal force");
    case RowKind::kMaxNormal:
      return absl::StrCat(who, " maximum normal force");
  }
  return who;
}

ConstraintRows BuildConstraintRows(const PlanProblem& problem,
                                   const MeasurementEllipsoid& ellipsoid,
                                   int cone_sides, double confidence,
                                   bool with_friction_facets) {
  const int n = static_cast<int>(problem.contacts.size());
  int m = 0;
  for (const Contact& c : problem.contacts) {
    m += (with_friction_facets ? cone_sides : 0) + 1 + (c.max_normal_force > 0.0 ? 1 : 0);
  }
  ConstraintRows rows;
  rows.matrix.setZero(m, 3 * n);
  rows.rhs.resize(m);
  rows.nominal_rhs.resize(m);
  rows.info.reserve(m);

  const double cos_half = std::cos(std::numbers::pi / cone_sides);
  int r = 0;
  Eigen::Matrix3d s_ii;  // covariance block of the contact being added
  auto add = [&](int contact, const Vec3& a, double d, RowKind kind, int facet) {
    rows.matrix.block<1, 3>(r, 3 * contact) = a.transpose();
    rows.nominal_rhs(r) = d;
    rows.rhs(r) = d - confidence * std::sqrt(std::max(0.0, a.dot(s_ii * a)));
    rows.info.push_back({contact, kind, facet});
    ++r;
  };
  for (int i = 0; i < n; ++i) {
    const Contact& c = problem.contacts[i];
    s_ii = ellipsoid.ContactCovariance(i);
    if (with_friction_facets) {
      const auto [t1, t2] = TangentBasis(c.normal);
      for (int j = 0; j < cone_sides; ++j) {
        const double theta = 2.0 * std::numbers::pi * j / cone_sides;
        const Vec3 u = std::cos(theta) * t1 + std::sin(theta) * t2;
        add(i, u - c.friction * cos_half * c.normal, 0.0, RowKind::kFrictionFacet, j);
      }
    }
    add(i, -c.normal, -c.min_normal_force, RowKind::kMinNormal, 0);
    if (c.max_normal_force > 0.0) add(i, c.normal, c.max_normal_force, RowKind::kMaxNormal, 0);
  }
  return rows;
}

std::vector<double> NormalForceSigma(const PlanProblem& problem,
                                     const MeasurementEllipsoid& ellipsoid) {
  std::vector<double> out;
  for (int i = 0; i < static_cast<int>(problem.contacts.size()); ++i) {
    const Vec3& nrm = problem.contacts[i].normal;
    out.push_back(std::sqrt(std::max(0.0, nrm.dot(ellipsoid.ContactCovariance(i) * nrm))));
  }
  return out;
}

std::vector<double> TangentialForceSigma(const PlanProblem& problem,
                                         const MeasurementEllipsoid& ellipsoid) {
  std::vector<double> out;
  for (int i = 0; i < static_cast<int>(problem.contacts.size()); ++i) {
    const Vec3& nrm = problem.contacts[i].normal;
    const Eigen::Matrix3d p = Eigen::Matrix3d::Identity() - nrm * nrm.transpose();
    const Eigen::Matrix3d s = p * ellipsoid.ContactCovariance(i) * p;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(s, Eigen::EigenvaluesOnly);
    out.push_back(std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff())));
  }
  return out;
}

std::vector<double> ExactConeShift(const PlanProblem& problem,
                                   const std::vector<double>& normal_sigma,
                                   const std::vector<double>& tangential_sigma,
                                   double confidence) {
  std::vector<double> out(problem.contacts.size());
  for (size_t i = 0; i < out.size(); ++i) {
    out[i] = confidence * (problem.contacts[i].friction * normal_sigma[i] + tangential_sigma[i]);
  }
  return out;
}

double ExactConeSlack(const Vec3& normal, double mu, double shift, const Vec3& force) {
  const Vec3 tangential = force - normal.dot(force) * normal;
  return (mu * normal.dot(force) - shift) - tangential.norm();
}

PreparedProblem Prepare(PlanProblem validated, const PlanOptions& options) {
  PreparedProblem p;
  p.problem = std::move(validated);
  p.equilibrium = ComputeForceEquilibrium(p.problem, options.rank_tolerance);
  p.ellipsoid = ComputeMeasurementEllipsoid(p.problem, p.equilibrium);
  p.rows = BuildConstraintRows(p.problem, p.ellipsoid, options.cone_sides, options.confidence,
                               options.cone == ConeModel::kPyramid);
  p.normal_sigma = NormalForceSigma(p.problem, p.ellipsoid);
  p.tangential_sigma = TangentialForceSigma(p.problem, p.ellipsoid);
  if (options.cone == ConeModel::kExact) {
    p.cone_shift =
        ExactConeShift(p.problem, p.normal_sigma, p.tangential_sigma, options.confidence);
  }
  return p;
}

}  // namespace tactforce::planner
