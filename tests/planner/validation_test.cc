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
      {"tiny normal", [](PlanProblem& p, PlanOptions&) { p.contacts[1].normal = Vec3(1e-12, 0, 0); },
       "contacts[1].normal: zero length"},
      {"nan normal", [&](PlanProblem& p, PlanOptions&) { p.contacts[0].normal.x() = nan; },
       "contacts[0].normal:"},
      {"nan position", [&](PlanProblem& p, PlanOptions&) { p.contacts[1].position.y() = nan; },
       "contacts[1].position:"},
      {"negative friction", [](PlanProblem& p, PlanOptions&) { p.contacts[1].friction = -0.1; },
       "contacts[1].friction:"},
      {"negative sigma", [](PlanProblem& p, PlanOptions&) { p.contacts[0].sigma = -0.1; },
       "contacts[0].sigma:"},
      {"min > max", [](PlanProblem& p, PlanOptions&) {
         p.contacts[2].min_normal_force = 3;
         p.contacts[2].max_normal_force = 2;
       }, "contacts[2].min_normal_force:"},
      {"negative min", [](PlanProblem& p, PlanOptions&) { p.contacts[0].min_normal_force = -1; },
       "contacts[0].min_normal_force:"},
      {"negative max", [](PlanProblem& p, PlanOptions&) { p.contacts[0].max_normal_force = -1; },
       "contacts[0].max_normal_force:"},
      {"cone sides 2", [](PlanProblem&, PlanOptions& o) { o.cone_sides = 2; }, "cone_sides:"},
      {"cone sides 65", [](PlanProblem&, PlanOptions& o) { o.cone_sides = 65; }, "cone_sides:"},
      {"negative confidence", [](PlanProblem&, PlanOptions& o) { o.confidence = -1; },
       "confidence:"},
      {"too many contacts", [](PlanProblem& p, PlanOptions&) {
         while (p.contacts.size() <= 64) p.contacts.push_back(p.contacts[0]);
       }, "contacts:"},
  };
  for (const BadCase& c : cases) {
    PlanProblem p = Valid();
    PlanOptions o;
    c.spoil(p, o);
    absl::StatusOr<PlanProblem> v = ValidateProblem(p, o);
    ASSERT_FALSE(v.ok()) << c.name;
    EXPECT_EQ(v.status().code(), absl::StatusCode::kInvalidArgument) << c.name;
    EXPECT_EQ(v.status().message().rfind(c.field, 0), 0u)
        << c.name << ": " << v.status().message();
    // Every backend returns the same error, never a crash or a result.
    for (SolverKind kind : {SolverKind::kGeometric, SolverKind::kIpopt, SolverKind::kCrossCheck}) {
      absl::StatusOr<PlanResult> r = MakeSolver(kind)->Solve(p, o);
      ASSERT_FALSE(r.ok()) << c.name;
      EXPECT_EQ(r.status().message(), v.status().message());
    }
  }
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
