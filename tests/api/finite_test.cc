// The reflection walk under every answer (finite.h): the path of the first
// NaN or infinity, through singular and repeated submessages and maps.
#include "tactforce/api/finite.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <limits>

#include "tactforce/v1/audit.pb.h"
#include "tactforce/v1/inertia.pb.h"
#include "tactforce/v1/planner.pb.h"

namespace tactforce::api {
namespace {

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

v1::FrictionProbeResponse ThreeSteps() {
  v1::FrictionProbeResponse r;
  for (int k = 0; k < 3; ++k) {
    r.add_times(0.1 * k);
    r.add_probe_forces()->set_z(-1);
    v1::PlanResponse* step = r.mutable_holding()->add_steps();
    for (int i = 0; i < 3; ++i) step->add_forces()->set_x(1.0 + i);
    step->add_normal_forces(2.0);
  }
  return r;
}

TEST(FindNonFinite, AllFiniteIsNullopt) {
  EXPECT_EQ(FindNonFinite(ThreeSteps()), std::nullopt);
  EXPECT_TRUE(CheckFiniteAnswer(ThreeSteps()).ok());
  EXPECT_EQ(FindNonFinite(v1::AuditResponse()), std::nullopt);
}

TEST(FindNonFinite, NanInARepeatedSubmessageGivesItsPath) {
  v1::FrictionProbeResponse r = ThreeSteps();
  r.mutable_holding()->mutable_steps(1)->mutable_forces(2)->set_y(kNan);
  EXPECT_EQ(FindNonFinite(r), "holding.steps[1].forces[2].y");
  const absl::Status s = CheckFiniteAnswer(r);
  EXPECT_EQ(s.code(), absl::StatusCode::kInternal);
  EXPECT_THAT(std::string(s.message()), ::testing::StartsWith("holding.steps[1].forces[2].y: nan in the answer of "
                                                              "FrictionProbeResponse"));
}

TEST(FindNonFinite, RepeatedScalarsAndTheFirstInFieldOrder) {
  v1::FrictionProbeResponse r = ThreeSteps();
  r.mutable_holding()->mutable_steps(2)->set_normal_forces(0, -kInf);
  r.set_times(2, kInf);
  EXPECT_EQ(FindNonFinite(r), "times[2]");  // field 1 before field 3
  r.set_times(2, 0.2);
  EXPECT_EQ(FindNonFinite(r), "holding.steps[2].normal_forces[0]");
}

TEST(FindNonFinite, MapsAreNamedByKey) {
  v1::AuditResponse r;
  (*r.add_causes()->mutable_parameters())["width"] = 1.0;
  r.add_causes();
  (*r.mutable_causes(1)->mutable_parameters())["gain"] = kInf;
  EXPECT_EQ(FindNonFinite(r), "causes[1].parameters[\"gain\"]");
  (*r.mutable_causes(1)->mutable_parameters())["gain"] = 2.0;
  // Through the map each time: reflection reads a synced copy of it.
  auto weights = [&]() -> v1::DoubleList& { return (*r.mutable_causes(0)->mutable_array_parameters())["pi_weights"]; };
  weights().add_values(0.5);
  weights().add_values(kNan);
  EXPECT_EQ(FindNonFinite(r), "causes[0].array_parameters[\"pi_weights\"].values[1]");
  r.set_gain(kNan);  // field 5, after causes (2)
  EXPECT_EQ(FindNonFinite(r), "causes[0].array_parameters[\"pi_weights\"].values[1]");
  weights().set_values(1, 0.5);
  EXPECT_EQ(FindNonFinite(r), "gain");
}

// Infinity is a documented value of two inertia fields; NaN never is.
TEST(FindNonFinite, DocumentedInfinitiesPassNanDoesNot) {
  v1::FitInertiaResponse r;
  r.set_pseudo_inertia_min_eigenvalue(-kInf);
  r.mutable_errors()->set_riemannian(kInf);
  EXPECT_EQ(FindNonFinite(r), std::nullopt);
  r.mutable_errors()->set_riemannian(kNan);
  EXPECT_EQ(FindNonFinite(r), "errors.riemannian");
  r.mutable_errors()->set_riemannian(1.0);
  r.set_mass(kInf);
  EXPECT_EQ(FindNonFinite(r), "mass");
}

}  // namespace
}  // namespace tactforce::api
