// The reflection walk under every answer (finite.h): the path of the first
// NaN or infinity, through singular and repeated submessages and maps.
#include "tactforce/api/finite.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
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
  EXPECT_THAT(std::string(s.message()),
              ::testing::StartsWith("holding.steps[1].forces[2].y: nan in the answer of "
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
  auto weights = [&]() -> v1::DoubleList& {
    return (*r.mutable_causes(0)->mutable_array_parameters())["pi_weights"];
  };
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

// Every double slot of `message` (each repeated field given two entries
// first, submessages filled recursively), as a setter on a copy.
void FillEveryField(google::protobuf::Message* m) {
  const google::protobuf::Reflection* r = m->GetReflection();
  const google::protobuf::Descriptor* d = m->GetDescriptor();
  for (int i = 0; i < d->field_count(); ++i) {
    const google::protobuf::FieldDescriptor* f = d->field(i);
    using FD = google::protobuf::FieldDescriptor;
    if (f->cpp_type() == FD::CPPTYPE_MESSAGE) {
      if (f->is_repeated()) {
        for (int k = 0; k < 2; ++k) FillEveryField(r->AddMessage(m, f));
      } else {
        FillEveryField(r->MutableMessage(m, f));
      }
    } else if (f->cpp_type() == FD::CPPTYPE_DOUBLE) {
      if (f->is_repeated()) {
        r->AddDouble(m, f, 1.0);
        r->AddDouble(m, f, 2.0);
      } else {
        r->SetDouble(m, f, 1.0);
      }
    }
  }
}

// Sets the `n`-th double value (depth first) of `m` to `value`; false when
// there are fewer.
bool SetNthDouble(google::protobuf::Message* m, int* n, double value) {
  const google::protobuf::Reflection* r = m->GetReflection();
  const google::protobuf::Descriptor* d = m->GetDescriptor();
  using FD = google::protobuf::FieldDescriptor;
  for (int i = 0; i < d->field_count(); ++i) {
    const FD* f = d->field(i);
    if (f->cpp_type() == FD::CPPTYPE_MESSAGE) {
      const int count = f->is_repeated() ? r->FieldSize(*m, f) : 1;
      for (int k = 0; k < count; ++k) {
        google::protobuf::Message* sub =
            f->is_repeated() ? r->MutableRepeatedMessage(m, f, k) : r->MutableMessage(m, f);
        if (SetNthDouble(sub, n, value)) return true;
      }
    } else if (f->cpp_type() == FD::CPPTYPE_DOUBLE) {
      const int count = f->is_repeated() ? r->FieldSize(*m, f) : 1;
      for (int k = 0; k < count; ++k) {
        if ((*n)-- > 0) continue;
        if (f->is_repeated()) {
          r->SetRepeatedDouble(m, f, k, value);
        } else {
          r->SetDouble(m, f, value);
        }
        return true;
      }
    }
  }
  return false;
}

// The reflection-free check of Plan's answer finds exactly what the walk
// finds, with the same message, for a NaN or an infinity in every double
// of a PlanResponse (so a new field cannot slip past it).
TEST(CheckFiniteAnswer, PlanResponseFastPathAgreesWithTheWalkOnEveryField) {
  v1::PlanResponse full;
  FillEveryField(&full);
  ASSERT_TRUE(CheckFiniteAnswer(full).ok());
  int slots = 0;
  for (double bad : {kNan, kInf, -kInf}) {
    for (int n = 0;; ++n) {
      v1::PlanResponse r = full;
      int index = n;
      if (!SetNthDouble(&r, &index, bad)) break;
      const absl::Status fast = CheckFiniteAnswer(r);
      const absl::Status walk = CheckFiniteAnswer(static_cast<const google::protobuf::Message&>(r));
      EXPECT_FALSE(fast.ok()) << "double #" << n << ": " << walk;
      EXPECT_EQ(fast, walk) << "double #" << n;
      slots = std::max(slots, n + 1);
    }
  }
  EXPECT_GE(slots, 13);  // forces 2x3, normal_forces 2, sigma 2, objective, margin, cross_check 2
}

}  // namespace
}  // namespace tactforce::api
