#include "tactforce/planner/validation.h"

#include <cmath>
#include <functional>
#include <limits>

#include <gtest/gtest.h>

#include "tactforce/planner/solver.h"

namespace tactforce::planner {
namespace {

PlanProblem Valid() {
  PlanProblem p;
  p.object.mass = 0.1;
  for (int i = 0; i < 3; ++i) {
    Contact c;
    const double a = 2.0944 * i;
    c.position = Vec3(0.03 * std::cos(a), 0.03 * std::sin(a), 0);
    c.normal = -c.position * 2.0;  // not unit: normalised by validation
    c.friction = 0.6;
    c.sigma = 0.1;
    p.contacts.push_back(c);
  }
  return p;
}

struct BadCase {
  const char* name;
  std::function<void(PlanProblem&, PlanOptions&)> spoil;
  const char* field;
};

TEST(Validation, AcceptsValidInputAndNormalisesNormals) {
  absl::StatusOr<PlanProblem> v = ValidateProblem(Valid(), PlanOptions{});
  ASSERT_TRUE(v.ok()) << v.status();
  for (const Contact& c : v->contacts) EXPECT_NEAR(c.normal.norm(), 1.0, 1e-15);
}

TEST(Validation, EveryBadInputNamesItsField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  const std::vector<BadCase> cases = {
      {"no contacts", [](PlanProblem& p, PlanOptions&) { p.contacts.clear(); }, "contacts:"},
      {"nan mass", [&](PlanProblem& p, PlanOptions&) { p.object.mass = nan; }, "object.mass:"},
      {"negative mass", [](PlanProblem& p, PlanOptions&) { p.object.mass = -1; }, "object.mass:"},
      {"inf com", [&](PlanProblem& p, PlanOptions&) { p.object.com.x() = inf; }, "object.com:"},
      {"nan gravity", [&](PlanProblem& p, PlanOptions&) { p.object.gravity.z() = nan; },
       "object.gravity:"},
      {"nan wrench", [&](PlanProblem& p, PlanOptions&) { p.external_wrench.torque.y() = nan; },
       "external_wrench.torque:"},
      {"zero normal", [](PlanProblem& p, PlanOptions&) { p.contacts[2].normal.setZero(); },
       "contacts[2].normal: zero length"},
      {"tiny normal",
       [](PlanProblem& p, PlanOptions&) { p.contacts[1].normal = Vec3(1e-12, 0, 0); },
       "contacts[1].normal: zero length"},
      {"nan normal", [&](PlanProblem& p, PlanOptions&) { p.contacts[0].normal.x() = nan; },
       "contacts[0].normal:"},
      {"nan position", [&](PlanProblem& p, PlanOptions&) { p.contacts[1].position.y() = nan; },
       "contacts[1].position:"},
      {"negative friction", [](PlanProblem& p, PlanOptions&) { p.contacts[1].friction = -0.1; },
       "contacts[1].friction:"},
      {"negative sigma", [](PlanProblem& p, PlanOptions&) { p.contacts[0].sigma = -0.1; },
       "contacts[0].sigma:"},
      {"min > max",
       [](PlanProblem& p, PlanOptions&) {
         p.contacts[2].min_normal_force = 3;
         p.contacts[2].max_normal_force = 2;
       },
       "contacts[2].min_normal_force:"},
      {"negative min", [](PlanProblem& p, PlanOptions&) { p.contacts[0].min_normal_force = -1; },
       "contacts[0].min_normal_force:"},
      {"negative max", [](PlanProblem& p, PlanOptions&) { p.contacts[0].max_normal_force = -1; },
       "contacts[0].max_normal_force:"},
      {"cone sides 2", [](PlanProblem&, PlanOptions& o) { o.cone_sides = 2; }, "cone_sides:"},
      {"cone sides 65", [](PlanProblem&, PlanOptions& o) { o.cone_sides = 65; }, "cone_sides:"},
      {"negative confidence", [](PlanProblem&, PlanOptions& o) { o.confidence = -1; },
       "confidence:"},
      {"too many contacts",
       [](PlanProblem& p, PlanOptions&) {
         while (p.contacts.size() <= 64) p.contacts.push_back(p.contacts[0]);
       },
       "contacts:"},
      // Issue 16: finite magnitudes no grasp has (mass 1e308 gave OK with
      // "residual of nan").
      {"huge mass", [](PlanProblem& x, PlanOptions&) { x.object.mass = 1e308; }, "object.mass:"},
      {"huge com", [](PlanProblem& x, PlanOptions&) { x.object.com.x() = 1e200; }, "object.com:"},
      {"huge gravity", [](PlanProblem& x, PlanOptions&) { x.object.gravity.z() = -1e300; },
       "object.gravity:"},
      {"huge wrench", [](PlanProblem& x, PlanOptions&) { x.external_wrench.force.y() = 1e160; },
       "external_wrench.force:"},
      {"huge torque", [](PlanProblem& x, PlanOptions&) { x.external_wrench.torque.y() = -1e160; },
       "external_wrench.torque:"},
      {"huge position", [](PlanProblem& x, PlanOptions&) { x.contacts[1].position.z() = 1e155; },
       "contacts[1].position:"},
      {"huge friction", [](PlanProblem& x, PlanOptions&) { x.contacts[2].friction = 1e300; },
       "contacts[2].friction:"},
      {"huge sigma", [](PlanProblem& x, PlanOptions&) { x.contacts[0].sigma = 1e200; },
       "contacts[0].sigma:"},
      {"huge max force",
       [](PlanProblem& x, PlanOptions&) { x.contacts[0].max_normal_force = 1e300; },
       "contacts[0].max_normal_force:"},
  };
  for (const BadCase& c : cases) {
    PlanProblem p = Valid();
    PlanOptions o;
    c.spoil(p, o);
    absl::StatusOr<PlanProblem> v = ValidateProblem(p, o);
    ASSERT_FALSE(v.ok()) << c.name;
    EXPECT_EQ(v.status().code(), absl::StatusCode::kInvalidArgument) << c.name;
    EXPECT_EQ(v.status().message().rfind(c.field, 0), 0u) << c.name << ": " << v.status().message();
    // Every backend returns the same error, never a crash or a result.
    for (SolverKind kind : {SolverKind::kGeometric, SolverKind::kIpopt, SolverKind::kCrossCheck}) {
      absl::StatusOr<PlanResult> r = MakeSolver(kind)->Solve(p, o);
      ASSERT_FALSE(r.ok()) << c.name;
      EXPECT_EQ(r.status().message(), v.status().message());
    }
  }
}

// Issue 16 reproducers: finite inputs whose intermediate products overflow.
TEST(Validation, HugeFiniteInputsAreNamedNotSilentlyWrong) {
  // A normal longer than ~1.3e154 overflowed |n| to inf and became (0,0,0):
  // INFEASIBLE instead of the plan of the same, shorter normal.
  PlanProblem p = Valid();
  p.contacts[0].normal = Vec3(0, 0, 0);
  p.contacts[0].normal(0) = -1e155;
  PlanProblem q = Valid();
  q.contacts[0].normal = Vec3(-1, 0, 0);
  absl::StatusOr<PlanProblem> v = ValidateProblem(p, PlanOptions{});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_EQ(v->contacts[0].normal, Vec3(-1, 0, 0));
  const absl::StatusOr<PlanResult> huge =
      MakeSolver(SolverKind::kGeometric)->Solve(p, PlanOptions{});
  const absl::StatusOr<PlanResult> unit =
      MakeSolver(SolverKind::kGeometric)->Solve(q, PlanOptions{});
  ASSERT_TRUE(huge.ok() && unit.ok()) << huge.status() << unit.status();
  EXPECT_EQ(huge->status, PlanStatus::kOptimal);
  ASSERT_EQ(huge->forces.size(), unit->forces.size());
  for (size_t i = 0; i < huge->forces.size(); ++i) EXPECT_EQ(huge->forces[i], unit->forces[i]);
  // The largest finite components normalise too; a tiny one is still zero.
  p.contacts[0].normal =
      Vec3(std::numeric_limits<double>::max(), std::numeric_limits<double>::max(), 0);
  v = ValidateProblem(p, PlanOptions{});
  ASSERT_TRUE(v.ok()) << v.status();
  EXPECT_NEAR(v->contacts[0].normal.norm(), 1.0, 1e-15);
  p.contacts[0].normal = Vec3(1e-200, 0, 0);
  EXPECT_EQ(ValidateProblem(p, PlanOptions{}).status().message(),
            "contacts[0].normal: zero length");
}

TEST(Validation, InertiaMustBePhysical) {
  EXPECT_TRUE(ValidateInertia({1e-3, 2e-3, 2.5e-3, 0, 0, 0}).ok());
  EXPECT_TRUE(ValidateInertia({0, 0, 0, 0, 0, 0}).ok());  // a point mass
  for (const Inertia& bad :
       {Inertia{-1e-3, 2e-3, 2e-3, 0, 0, 0}, Inertia{1e-3, 1e-3, 5e-3, 0, 0, 0},
        Inertia{std::nan(""), 1e-3, 1e-3, 0, 0, 0}, Inertia{1e-3, 1e-3, 1e-3, 1e-2, 0, 0}}) {
    const absl::Status s = ValidateInertia(bad);
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << bad.ixx << " " << bad.izz;
    EXPECT_EQ(std::string(s.message()).rfind("object.inertia: ", 0), 0u) << s;
  }
}

TEST(Validation, InertiaMagnitudeIsBounded) {
  const absl::Status s = ValidateInertia({1e300, 1e300, 1e300, 0, 0, 0});
  EXPECT_EQ(s.message(), "object.inertia: component magnitude exceeds 1e+12 kg m^2");
}

TEST(Validation, MagnitudeChecksNameTheFieldAndTheLimit) {
  EXPECT_TRUE(CheckMagnitude("f", 1e9, kMaxForce, "N").ok());
  EXPECT_EQ(CheckMagnitude("f", -1.5e9, kMaxForce, "N").message(), "f: magnitude exceeds 1e+09 N");
  EXPECT_EQ(CheckMagnitude("f", std::nan(""), kMaxForce, "N").message(), "f: not a finite number");
  EXPECT_EQ(CheckMagnitude("p", Vec3(0, -1e300, 0), kMaxLength, "m").message(),
            "p: component magnitude exceeds 1000 m");
  EXPECT_EQ(
      CheckMagnitude("p", Vec3(0, std::numeric_limits<double>::infinity(), 0), kMaxLength, "m")
          .message(),
      "p: not a finite vector");
  EXPECT_FALSE(IsBounded(std::nan(""), 1.0));
}

TEST(Validation, TimesAreBoundedAndStepsResolved) {
  const double previous = 1.0;
  EXPECT_TRUE(CheckTime("t", 1.0 + 1e-6, &previous).ok());
  EXPECT_TRUE(CheckTime("t", 1.7e9).ok());  // an epoch clock
  EXPECT_EQ(CheckTime("t", 1e13).message(), "t: magnitude exceeds 1e+12 s");
  EXPECT_EQ(CheckTime("t", 1.0 + 1e-12, &previous).message().substr(0, 8), "t: step ");
  const double tiny = 1e-302;
  EXPECT_EQ(
      CheckTime("samples[1].t", 2e-302, &tiny).message(),
      "samples[1].t: step 1e-302 s after the previous sample is below the resolution 1e-09 s");
}

TEST(Validation, DirectionsOfAnyFiniteLengthAreNormalisedWithoutOverflow) {
  for (const Vec3& v : {Vec3(0, 0, -1e155), Vec3(1e300, -1e300, 1e300), Vec3(3e-9, 4e-9, 0)}) {
    Vec3 n = v;
    ASSERT_TRUE(NormalizeDirection(&n)) << v.transpose();
    EXPECT_NEAR(n.norm(), 1.0, 1e-15);
    EXPECT_NEAR(n.dot(v / v.cwiseAbs().maxCoeff()), (v / v.cwiseAbs().maxCoeff()).norm(), 1e-12);
  }
  Vec3 zero(1e-10, 0, 0);
  EXPECT_FALSE(NormalizeDirection(&zero));
  EXPECT_EQ(zero, Vec3(1e-10, 0, 0));
}

TEST(Validation, TrajectoryStepsAndProbesNameTheirFields) {
  TrajectoryStep step;
  EXPECT_TRUE(ValidateTrajectoryStep(step, 0, false).ok());
  step.linear_acceleration.z() = 1e155;
  EXPECT_EQ(ValidateTrajectoryStep(step, 3, true).message(),
            "steps[3].linear_acceleration: component magnitude exceeds 10000 m/s^2");
  step = TrajectoryStep{};
  step.angular_velocity.x() = 1.0;
  EXPECT_EQ(ValidateTrajectoryStep(step, 1, false).message(),
            "object.inertia: required because steps[1] rotates the object");

  FrictionProbe probe;
  probe.normal = Vec3(0, 0, -1e155);
  probe.tangent = Vec3(1e300, 0, 1e300);  // projected: +x
  Vec3 n, t;
  ASSERT_TRUE(ValidateFrictionProbe(probe, &n, &t).ok());
  EXPECT_NEAR((n - Vec3(0, 0, -1)).norm(), 0.0, 1e-15);
  EXPECT_NEAR((t - Vec3(1, 0, 0)).norm(), 0.0, 1e-15);
  probe.tangential_force = 1e155;
  EXPECT_EQ(ValidateFrictionProbe(probe, &n, &t).message(),
            "probe.tangential_force: magnitude exceeds 1e+09 N");
}

TEST(Validation, GeometricBackendRejectsExactCone) {
  PlanOptions o;
  o.cone = ConeModel::kExact;
  absl::StatusOr<PlanResult> r = MakeSolver(SolverKind::kGeometric)->Solve(Valid(), o);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
  EXPECT_NE(r.status().message().find("cone"), std::string::npos);
}

}  // namespace
}  // namespace tactforce::planner
