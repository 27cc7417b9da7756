// Robust plans under uncertain inertial parameters and friction (issue 28):
// the exactness property over seeded random grasps on both backends, zero
// covariance bit-identical, attribution of infeasibility, bad covariances.
#include "tactforce/planner/parameter_uncertainty.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>

#include <Eigen/Eigenvalues>
#include <Eigen/QR>
#include <gtest/gtest.h>

#include "absl/strings/str_cat.h"
#include "planner/fixtures.h"
#include "tactforce/planner/random_grasps.h"
#include "tactforce/planner/solver.h"
#include "tactforce/planner/trajectory.h"

namespace tactforce::planner {
namespace {

using fixtures::Options;

// Cases are drawn at test time from fixed seeds (deterministic).
constexpr uint64_t kSeed = 28;

// A random covariance of pi scaled to the object: mass ~ 5 %, CoM ~ 3 mm,
// inertia ~ 10 % of m r^2, with random correlations.
Matrix10d RandomCovariance(std::mt19937_64& rng, double mass) {
  std::normal_distribution<double> normal;
  const double r = 0.05;
  Vector10d scale;
  scale << 0.05 * mass, Eigen::Vector3d::Constant(mass * 0.003),
      Eigen::Matrix<double, 6, 1>::Constant(0.1 * mass * r * r);
  Matrix10d a;
  for (int i = 0; i < 10; ++i)
    for (int j = 0; j < 10; ++j) a(i, j) = normal(rng);
  return scale.asDiagonal() * (a * a.transpose() / 10.0) * scale.asDiagonal();
}

Matrix10d Factor(const Matrix10d& s) {
  const Eigen::SelfAdjointEigenSolver<Matrix10d> eig(s);
  return eig.eigenvectors() * eig.eigenvalues().cwiseMax(0.0).cwiseSqrt().asDiagonal();
}

// A point of the unit ball in `dim` dimensions, on its boundary when `edge`.
Eigen::VectorXd BallPoint(std::mt19937_64& rng, int dim, bool edge) {
  std::normal_distribution<double> normal;
  Eigen::VectorXd z(dim);
  for (int i = 0; i < dim; ++i) z(i) = normal(rng);
  const double radius =
      edge ? 1.0 : std::pow(std::uniform_real_distribution<double>(0, 1)(rng), 1.0 / dim);
  return dim == 0 ? z : (radius / z.norm()) * z;
}

struct Case {
  PlanProblem problem;
  PlanOptions options;
};

Case RandomCase(std::mt19937_64& rng, ConeModel cone) {
  RandomGraspOptions go;
  go.min_contacts = 3;
  go.infeasible_fraction = 0.0;
  Case c{MakeRandomGrasp(rng, go).problem, Options(cone, 0.0)};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  c.options.confidence = 0.5 + 1.5 * u(rng);
  PlanProblem& p = c.problem;
  p.object.uncertainty.covariance = RandomCovariance(rng, p.object.mass);
  if (u(rng) < 0.5) p.object.uncertainty.confidence = 0.5 + 2.5 * u(rng);
  for (Contact& contact : p.contacts) {
    if (u(rng) < 0.5) contact.friction_sigma = 0.2 * contact.friction * u(rng);
  }
  if (u(rng) < 0.5) {  // a moving object: the regressor at this instant
    p.motion.linear_acceleration = Vec3::Random();
    p.motion.angular_velocity = 2.0 * Vec3::Random();
    p.motion.angular_acceleration = 5.0 * Vec3::Random();
  }
  return c;
}

// G^+ computed independently of the planner (complete orthogonal decomposition).
Eigen::MatrixXd PseudoInverse(const PreparedProblem& prepared) {
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(prepared.equilibrium.grasp_matrix);
  cod.setThreshold(1e-9);
  return cod.pseudoInverse();
}

// Largest violation (N, > 0 violated) of the UNTIGHTENED rows with a friction
// mu' drawn in [mu - kappa sigma, mu + kappa sigma] (>= the planning mu).
double WorstViolation(const PreparedProblem& prep, const PlanProblem& request,
                      const PlanOptions& options, const Eigen::VectorXd& f, std::mt19937_64& rng) {
  double worst = -1e300;
  const int k = options.cone_sides;
  for (int i = 0; i < prep.num_contacts(); ++i) {
    const Contact& c = prep.problem.contacts[i];
    const double sigma = request.contacts[i].friction_sigma * options.confidence;
    const double mu = std::uniform_real_distribution<double>(
        c.friction, request.contacts[i].friction + sigma)(rng);
    const Vec3 fi = f.segment<3>(3 * i);
    const double fn = c.normal.dot(fi);
    worst = std::max(worst, c.min_normal_force - fn);
    if (c.max_normal_force > 0) worst = std::max(worst, fn - c.max_normal_force);
    if (options.cone == ConeModel::kExact) {
      worst = std::max(worst, -ExactConeSlack(c.normal, mu, 0.0, fi));
      continue;
    }
    const auto [t1, t2] = TangentBasis(c.normal);
    for (int j = 0; j < k; ++j) {
      const double th = 2.0 * std::numbers::pi * j / k;
      const Vec3 a =
          std::cos(th) * t1 + std::sin(th) * t2 - mu * std::cos(std::numbers::pi / k) * c.normal;
      worst = std::max(worst, a.dot(fi));
    }
  }
  return worst;
}

struct Tally {
  int optimal = 0, samples = 0, violations = 0;
  double worst = -1e300, support_error = 0.0, tight_error = 0.0;
};

void CheckExactness(SolverKind kind, ConeModel cone, uint64_t seed, int grasps, int per_grasp,
                    Tally* t) {
  std::mt19937_64 rng(seed);
  for (int g = 0; g < grasps; ++g) {
    const Case c = RandomCase(rng, cone);
    absl::StatusOr<PlanResult> r = Plan(c.problem, c.options, kind);
    ASSERT_TRUE(r.ok()) << r.status();
    if (r->status != PlanStatus::kOptimal) continue;
    ++t->optimal;
    const PreparedProblem prep = fixtures::Prepared(c.problem, c.options);
    const Eigen::MatrixXd pinv = PseudoInverse(prep);
    const Eigen::MatrixXd param_factor =
        pinv * WrenchRegressor(prep.problem.object.gravity, c.problem.motion) *
        Factor(c.problem.object.uncertainty.covariance);  // 3n x 10
    const double kappa_b = prep.parameters.confidence;
    Eigen::VectorXd f(3 * prep.num_contacts());
    for (int i = 0; i < prep.num_contacts(); ++i) f.segment<3>(3 * i) = r->forces[i];
    // The reported parameter margin is the support function, computed apart.
    for (const RowMargin& m : r->row_margins) {
      if (m.cone) continue;
      const Eigen::VectorXd a = prep.rows.Dense(prep.num_contacts()).row(m.row).transpose();
      const double support = kappa_b * (param_factor.transpose() * a).norm();
      t->support_error =
          std::max(t->support_error, std::abs(support - m.parameters) / std::max(1.0, support));
    }
    const Eigen::MatrixXd& meas = prep.ellipsoid.factor;
    // Each row's own worst case (both ellipsoids' maximisers): its value
    // is exactly d - slack, so the active rows are met with equality.
    for (const RowMargin& m : r->row_margins) {
      if (m.cone) continue;
      const Eigen::VectorXd a = prep.rows.Dense(prep.num_contacts()).row(m.row).transpose();
      Eigen::VectorXd df = Eigen::VectorXd::Zero(f.size());
      const Eigen::VectorXd zp = param_factor.transpose() * a, zm = meas.transpose() * a;
      if (zp.norm() > 0) df += kappa_b * param_factor * zp.normalized();
      if (meas.cols() > 0 && zm.norm() > 0) df += c.options.confidence * meas * zm.normalized();
      const double value = a.dot(f + df) - prep.rows.nominal_rhs(m.row);
      t->tight_error = std::max(
          t->tight_error, std::abs(value + m.slack) / std::max(1.0, f.lpNorm<Eigen::Infinity>()));
    }
    for (int s = 0; s < per_grasp; ++s) {
      const bool edge = s % 2 == 0;
      Eigen::VectorXd df = kappa_b * param_factor * BallPoint(rng, 10, edge);
      if (meas.cols() > 0)
        df += c.options.confidence * meas * BallPoint(rng, int(meas.cols()), edge);
      const double v = WorstViolation(prep, c.problem, c.options, f + df, rng);
      t->worst = std::max(t->worst, v);
      ++t->samples;
      if (v > 1e-9 * std::max(1.0, f.lpNorm<Eigen::Infinity>())) ++t->violations;
    }
  }
}

TEST(ParameterUncertainty, SampledParametersSatisfyUntightenedRowsGeometric) {
  Tally t;
  CheckExactness(SolverKind::kGeometric, ConeModel::kPyramid, 2801, 200, 100, &t);
  SCOPED_TRACE(testing::Message() << "optimal " << t.optimal << " samples " << t.samples
                                  << " worst " << t.worst);
  EXPECT_GE(t.optimal, 100);
  EXPECT_EQ(t.violations, 0);
  EXPECT_GE(t.samples, 10000);
  EXPECT_LE(t.support_error, 1e-9);
  EXPECT_LE(t.tight_error, 1e-9);
  std::printf(
      "GEOMETRIC pyramid: %d optimal of 200 grasps, %d samples, %d violations, worst %.3g N, "
      "support error %.2g, row worst-case error %.2g\n",
      t.optimal, t.samples, t.violations, t.worst, t.support_error, t.tight_error);
}

TEST(ParameterUncertainty, SampledParametersSatisfyUntightenedRowsIpopt) {
  for (ConeModel cone : {ConeModel::kPyramid, ConeModel::kExact}) {
    Tally t;
    CheckExactness(SolverKind::kIpopt, cone, 28 + static_cast<int>(cone), 30, 50, &t);
    SCOPED_TRACE(testing::Message()
                 << "cone " << int(cone) << " optimal " << t.optimal << " worst " << t.worst);
    EXPECT_GE(t.optimal, 10);
    std::printf(
        "IPOPT %s: %d optimal of 30 grasps, %d samples, %d violations (1e-9 N), worst %.3g N\n",
        cone == ConeModel::kExact ? "exact" : "pyramid", t.optimal, t.samples, t.violations,
        t.worst);
    // Ipopt stops within its tolerance of the tightened boundary.
    EXPECT_LE(t.worst, 1e-6);
  }
}

TEST(ParameterUncertainty, CrossCheckAgreesWithUncertainty) {
  std::mt19937_64 rng(kSeed + __LINE__);
  int compared = 0;
  for (int g = 0; g < 40; ++g) {
    const Case c = RandomCase(rng, ConeModel::kPyramid);
    absl::StatusOr<PlanResult> r = Plan(c.problem, c.options, SolverKind::kCrossCheck);
    ASSERT_TRUE(r.ok()) << r.status();
    ASSERT_TRUE(r->cross_check.has_value());
    EXPECT_TRUE(r->cross_check->agree) << r->message << " diff " << r->cross_check->max_force_diff;
    if (r->status == PlanStatus::kOptimal) {
      ++compared;
      EXPECT_LE(r->cross_check->max_force_diff, 1e-5);
    }
  }
  EXPECT_GE(compared, 15);
}

bool SameBits(const PlanResult& a, const PlanResult& b) {
  if (a.status != b.status || a.forces.size() != b.forces.size()) return false;
  for (size_t i = 0; i < a.forces.size(); ++i) {
    if (std::memcmp(a.forces[i].data(), b.forces[i].data(), sizeof(double) * 3) != 0) return false;
  }
  return std::memcmp(&a.min_margin, &b.min_margin, sizeof(double)) == 0 && a.message == b.message &&
         a.row_margins.empty() && b.row_margins.empty();
}

TEST(ParameterUncertainty, ZeroCovarianceIsBitIdentical) {
  std::mt19937_64 rng(kSeed + __LINE__);
  for (int g = 0; g < 100; ++g) {
    RandomGraspOptions go;
    PlanProblem plain = MakeRandomGrasp(rng, go).problem;
    PlanProblem zero = plain;
    zero.object.uncertainty.confidence = 3.0;  // a confidence without a covariance
    zero.motion.angular_velocity = Vec3(1, 2, 3);
    for (Contact& c : zero.contacts) c.friction_sigma = 0.0;
    const PlanOptions o = Options(ConeModel::kPyramid, 1.5);
    absl::StatusOr<PlanResult> a = Plan(plain, o, SolverKind::kGeometric);
    absl::StatusOr<PlanResult> b = Plan(zero, o, SolverKind::kGeometric);
    ASSERT_TRUE(a.ok() && b.ok());
    EXPECT_TRUE(SameBits(*a, *b)) << g;
    // The prepared rows are those of the measurement-only construction.
    const PreparedProblem prep = fixtures::Prepared(zero, o);
    const ConstraintRows rows =
        BuildConstraintRows(prep.problem, prep.ellipsoid, o.cone_sides, o.confidence, true);
    ASSERT_EQ(rows.rhs.size(), prep.rows.rhs.size());
    EXPECT_EQ(std::memcmp(rows.rhs.data(), prep.rows.rhs.data(), sizeof(double) * rows.rhs.size()),
              0);
    EXPECT_FALSE(prep.parameters.active);
  }
}

// Antipodal pinch with the CoM at the origin: mass errors only move the
// weight, which friction must carry (mu fn >= m g / 2 per finger).
PlanProblem BoundedPinch(double max_force) {
  PlanProblem p = fixtures::Pinch(0.2, 0.5);
  for (Contact& c : p.contacts) c.max_normal_force = max_force;
  return p;
}

UncertaintySource SourceOf(const PlanProblem& p, SolverKind kind) {
  absl::StatusOr<PlanResult> r = Plan(p, Options(ConeModel::kPyramid, 2.0), kind);
  EXPECT_TRUE(r.ok());
  EXPECT_NE(r->status, PlanStatus::kOptimal) << ToString(r->infeasible_source);
  return r->infeasible_source;
}

TEST(ParameterUncertainty, InfeasibilityNamesTheSource) {
  // Nominal need: fn = m g / (2 mu cos(pi/12)) ~ 2.03 N per finger.
  for (SolverKind kind : {SolverKind::kGeometric, SolverKind::kIpopt}) {
    PlanProblem mass = BoundedPinch(2.6);
    mass.object.uncertainty.covariance =
        CovarianceFromMassAndCom(0.2, Vec3::Zero(), 0.05, Eigen::Matrix3d::Zero());
    EXPECT_EQ(SourceOf(mass, kind), UncertaintySource::kParameters);
    absl::StatusOr<PlanResult> r = Plan(mass, Options(ConeModel::kPyramid, 2.0), kind);
    EXPECT_NE(r->message.find("inertial-parameter"), std::string::npos) << r->message;

    PlanProblem friction = BoundedPinch(2.6);
    for (Contact& c : friction.contacts) c.friction_sigma = 0.1;
    EXPECT_EQ(SourceOf(friction, kind), UncertaintySource::kFriction);

    PlanProblem measurement = BoundedPinch(2.6);
    for (Contact& c : measurement.contacts) c.sigma = 1.0;
    measurement.contacts[0].friction_sigma = 1e-4;  // model uncertainty present, negligible
    EXPECT_EQ(SourceOf(measurement, kind), UncertaintySource::kMeasurement);

    PlanProblem nominal = BoundedPinch(1.5);
    nominal.object.uncertainty.covariance = mass.object.uncertainty.covariance;
    EXPECT_EQ(SourceOf(nominal, kind), UncertaintySource::kNominal);
  }
}

TEST(ParameterUncertainty, FeasibleWithSmallUncertaintyReportsBothParts) {
  PlanProblem p = BoundedPinch(0.0);
  for (Contact& c : p.contacts) c.sigma = 0.2;
  p.object.uncertainty.covariance =
      CovarianceFromMassAndCom(0.2, Vec3::Zero(), 0.01, Eigen::Matrix3d::Zero());
  absl::StatusOr<PlanResult> r = Plan(p, Options(ConeModel::kPyramid, 1.0), SolverKind::kGeometric);
  ASSERT_TRUE(r.ok());
  ASSERT_EQ(r->status, PlanStatus::kOptimal) << r->message;
  ASSERT_FALSE(r->row_margins.empty());
  double meas = 0, param = 0;
  for (const RowMargin& m : r->row_margins)
    meas = std::max(meas, m.measurement), param = std::max(param, m.parameters);
  EXPECT_GT(meas, 0.0);
  // Mass error 0.01 kg moves the weight by 0.0981 N shared by two fingers.
  EXPECT_GT(param, 0.0);
  EXPECT_LT(param, 0.0981);
}

absl::Status Validate(const Matrix10d& s) {
  PlanProblem p = fixtures::Pinch(0.2, 0.5);
  p.object.uncertainty.covariance = s;
  return ValidateProblem(p, PlanOptions{}).status();
}

TEST(ParameterUncertainty, BadCovarianceNamesFieldAndIndex) {
  std::mt19937_64 rng(kSeed + __LINE__);
  const Matrix10d good = RandomCovariance(rng, 0.3);
  EXPECT_TRUE(Validate(good).ok());
  const int i = std::uniform_int_distribution<int>(0, 9)(rng);
  int j = std::uniform_int_distribution<int>(0, 8)(rng);
  if (j >= i) ++j;
  Matrix10d asym = good;
  asym(std::min(i, j), std::max(i, j)) += 1.0;
  absl::Status s = Validate(asym);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find(absl::StrCat("object.uncertainty.covariance[",
                                          std::min(i, j) * 10 + std::max(i, j), "]")),
            std::string::npos)
      << s;
  Matrix10d nan = good;
  nan(i, j) = std::nan("");
  s = Validate(nan);
  EXPECT_NE(s.message().find(
                absl::StrCat("object.uncertainty.covariance[", i * 10 + j, "]: not a finite")),
            std::string::npos)
      << s;
  // Not PSD: a negative eigenvalue along parameter i.
  Matrix10d indefinite =
      good - 2.0 * good.diagonal().maxCoeff() * Vector10d::Unit(i) * Vector10d::Unit(i).transpose();
  s = Validate(indefinite);
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(s.message().find(absl::StrCat("object.uncertainty.covariance[", i * 11, "]")),
            std::string::npos)
      << s;
  PlanProblem p = fixtures::Pinch(0.2, 0.5);
  p.object.uncertainty.confidence = -1;
  EXPECT_NE(
      ValidateProblem(p, PlanOptions{}).status().message().find("object.uncertainty.confidence"),
      std::string::npos);
  p = fixtures::Pinch(0.2, 0.5);
  p.contacts[1].friction_sigma = -0.1;
  EXPECT_NE(ValidateProblem(p, PlanOptions{}).status().message().find("contacts[1].friction_sigma"),
            std::string::npos);
}

// PlanTrajectory takes the regressor of each step: an inertia-only
// covariance costs nothing at rest and a margin while the object turns.
TEST(ParameterUncertainty, TrajectoryUsesTheStepRegressor) {
  TrajectoryProblem t;
  t.base = fixtures::ThreeFingerGrasp(4, 0.1);
  t.inertia = Inertia{1e-3, 1e-3, 1e-3, 0, 0, 0};
  for (int k = 4; k < 10; ++k) t.base.object.uncertainty.covariance(k, k) = 1e-8;
  t.steps.resize(2);
  t.steps[1].angular_acceleration = Vec3(0, 0, 20.0);
  absl::StatusOr<TrajectoryResult> r =
      PlanTrajectory(t, Options(ConeModel::kPyramid, 1.0), SolverKind::kGeometric);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_EQ(r->optimal, 2);
  double at_rest = 0, turning = 0;
  for (const RowMargin& m : r->steps[0].row_margins) at_rest = std::max(at_rest, m.parameters);
  for (const RowMargin& m : r->steps[1].row_margins) turning = std::max(turning, m.parameters);
  EXPECT_EQ(at_rest, 0.0);
  EXPECT_GT(turning, 0.0);
}

TEST(ParameterUncertainty, RegressorMatchesNewtonEuler) {
  std::mt19937_64 rng(kSeed + __LINE__);
  std::uniform_real_distribution<double> u(-1, 1);
  for (int k = 0; k < 20; ++k) {
    const double m = 0.1 + std::abs(u(rng));
    const Vec3 c = 0.05 * Vec3(u(rng), u(rng), u(rng));
    Eigen::Matrix3d a = Eigen::Matrix3d::Random();
    const Eigen::Matrix3d ic = 1e-3 * (a * a.transpose() + Eigen::Matrix3d::Identity());
    const Motion motion{Vec3(u(rng), u(rng), u(rng)), 3 * Vec3(u(rng), u(rng), u(rng)),
                        5 * Vec3(u(rng), u(rng), u(rng))};
    const Vec3 g(0, 0, -9.81);
    const Eigen::Matrix<double, 6, 1> b = WrenchRegressor(g, motion) * StandardParameters(m, c, ic);
    // Newton-Euler directly about the CoM, then moved to the origin.
    const Vec3 acc_com = motion.linear_acceleration + motion.angular_acceleration.cross(c) +
                         motion.angular_velocity.cross(motion.angular_velocity.cross(c));
    const Vec3 force = m * (acc_com - g);
    const Vec3 torque = ic * motion.angular_acceleration +
                        motion.angular_velocity.cross(ic * motion.angular_velocity) +
                        c.cross(force);
    EXPECT_LE((b.head<3>() - force).norm(), 1e-12 * std::max(1.0, force.norm()));
    EXPECT_LE((b.tail<3>() - torque).norm(), 1e-12 * std::max(1.0, torque.norm()));
  }
}

}  // namespace
}  // namespace tactforce::planner
