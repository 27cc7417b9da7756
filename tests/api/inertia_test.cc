// The FitInertia request stream and the inertia conversions, in process.
#include "tactforce/api/inertia.h"

#include <gtest/gtest.h>

#include "tactforce/inertia/simulate.h"

namespace tactforce::api {
namespace {

inertia::SimulationResult Simulated(inertia::SimulationMode mode, bool kinematics) {
  inertia::SimulationOptions o;
  o.mode = mode;
  o.duration = 2.0;
  o.rate_hz = 100.0;
  o.write_kinematics = kinematics;
  o.seed = 3;
  absl::StatusOr<inertia::SimulationResult> r = inertia::SimulateInertia(o);
  EXPECT_TRUE(r.ok()) << r.status();
  return *r;
}

v1::FitInertiaRequest Batch(const inertia::InertiaSamples& s, size_t begin, size_t end) {
  v1::FitInertiaRequest m;
  for (size_t i = begin; i < end; ++i) *m.add_samples() = InertiaSampleToProto(s.samples[i], s.source);
  return m;
}

// Converting every sample to proto and streaming it back reproduces the
// samples exactly (wrench and contacts, with and without kinematics), so
// the fit equals the direct one.
TEST(InertiaStream, RoundTripGivesTheDirectFit) {
  for (auto mode : {inertia::SimulationMode::kWristWrench, inertia::SimulationMode::kInHand}) {
    for (bool kinematics : {false, true}) {
      const inertia::SimulationResult sim = Simulated(mode, kinematics);
      const inertia::InertiaSamples& s = sim.samples;
      InertiaStream stream;
      const size_t n = s.samples.size();
      for (size_t b = 0; b < n; b += 37) ASSERT_TRUE(stream.Add(Batch(s, b, std::min(n, b + 37))).ok());
      EXPECT_EQ(stream.samples_received(), static_cast<int64_t>(n));
      v1::InertiaFitOptions options;
      options.set_method(v1::INERTIA_METHOD_BASELINE_LS);
      absl::StatusOr<v1::FitInertiaResponse> streamed = stream.Fit();
      ASSERT_TRUE(streamed.ok()) << streamed.status();
      absl::StatusOr<v1::FitInertiaResponse> direct = FitInertiaSamples(s, v1::InertiaFitOptions());
      ASSERT_TRUE(direct.ok()) << direct.status();
      EXPECT_EQ(streamed->mass(), direct->mass());
      EXPECT_EQ(streamed->inertia().izz(), direct->inertia().izz());
      EXPECT_EQ(streamed->com().x(), direct->com().x());
      EXPECT_EQ(streamed->method(), v1::INERTIA_METHOD_CONSTRAINED);  // the default
      EXPECT_FALSE(streamed->has_errors());  // no truth given
    }
  }
}

TEST(InertiaStream, ResponseRoundTripsThroughTheLibraryType) {
  const inertia::SimulationResult sim = Simulated(inertia::SimulationMode::kWristWrench, true);
  v1::InertiaFitOptions options;
  *options.mutable_truth() = InertialParametersToProto(sim.truth.params);
  absl::StatusOr<v1::FitInertiaResponse> r = FitInertiaSamples(sim.samples, options);
  ASSERT_TRUE(r.ok()) << r.status();
  ASSERT_TRUE(r->has_errors());
  EXPECT_TRUE(r->errors().consistent());
  // Noise-free measured kinematics: the estimate is close to the truth.
  EXPECT_LT(r->errors().mass_percent(), 0.1);
  EXPECT_LT(r->errors().riemannian(), 0.05);
  const inertia::InertiaFit back = InertiaFitFromProto(*r);
  const v1::FitInertiaResponse again = InertiaFitToProto(back);
  EXPECT_EQ(again.mass(), r->mass());
  EXPECT_EQ(again.inertia().iyz(), r->inertia().iyz());
  EXPECT_EQ(again.principal_axes(2).z(), r->principal_axes(2).z());
  EXPECT_EQ(again.singular_values_size(), r->singular_values_size());
  EXPECT_EQ(again.physically_consistent(), r->physically_consistent());
}

TEST(InertiaStream, InconsistentMessagesAreNamed) {
  const inertia::SimulationResult wrench = Simulated(inertia::SimulationMode::kWristWrench, false);
  const inertia::SimulationResult hand = Simulated(inertia::SimulationMode::kInHand, false);
  {
    InertiaStream stream;
    ASSERT_TRUE(stream.Add(Batch(wrench.samples, 0, 10)).ok());
    const absl::Status s = stream.Add(Batch(hand.samples, 10, 12));
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(s.message().find("samples[10]: wrench expected"), std::string::npos) << s;
  }
  {
    InertiaStream stream;
    ASSERT_TRUE(stream.Add(Batch(hand.samples, 0, 10)).ok());
    const absl::Status s = stream.Add(Batch(wrench.samples, 10, 11));
    EXPECT_NE(s.message().find("samples[10].wrench: contacts expected"), std::string::npos) << s;
  }
  {
    InertiaStream stream;
    v1::FitInertiaRequest m;
    m.add_samples()->set_t(0.0);  // neither wrench nor contacts
    const absl::Status s = stream.Add(m);
    EXPECT_NE(s.message().find("samples[0]: give exactly one force source"), std::string::npos) << s;
  }
  {
    InertiaStream stream(/*max_samples=*/5);
    const absl::Status s = stream.Add(Batch(wrench.samples, 0, 6));
    EXPECT_NE(s.message().find("more than 5 samples"), std::string::npos) << s;
  }
  {
    InertiaStream stream;
    v1::FitInertiaRequest m = Batch(wrench.samples, 0, 3);
    m.mutable_options()->set_method(v1::INERTIA_METHOD_BASELINE_LS);
    ASSERT_TRUE(stream.Add(m).ok());
    const absl::StatusOr<v1::FitInertiaResponse> r = stream.Fit();
    EXPECT_EQ(r.status().code(), absl::StatusCode::kInvalidArgument);
    EXPECT_NE(r.status().message().find("3 sample(s), at least 4 needed"), std::string::npos) << r.status();
  }
  {
    // A sample whose contact count differs from the first: the library's
    // validation names it at the fit.
    InertiaStream stream;
    v1::FitInertiaRequest m = Batch(hand.samples, 0, 20);
    m.mutable_samples(13)->mutable_contacts()->RemoveLast();
    ASSERT_TRUE(stream.Add(m).ok());
    const absl::StatusOr<v1::FitInertiaResponse> r = stream.Fit();
    EXPECT_NE(r.status().message().find("samples[13]: 3 contacts, expected 4"), std::string::npos)
        << r.status();
  }
}

TEST(InertiaOptionsFromProto, ValidatesAndNamesFields) {
  v1::InertiaFitOptions o;
  o.set_method(static_cast<v1::InertiaMethod>(42));
  EXPECT_NE(InertiaOptionsFromProto(o).status().message().find("options.method: unknown value 42"),
            std::string::npos);
  o.Clear();
  for (int i = 0; i < 3; ++i) *o.add_hull() = v1::Vec3();  // too few points
  EXPECT_NE(InertiaOptionsFromProto(o).status().message().find("options.hull"), std::string::npos)
      << InertiaOptionsFromProto(o).status();
  o.Clear();
  o.mutable_truth()->set_mass(-1.0);
  EXPECT_NE(InertiaOptionsFromProto(o).status().message().find("options.truth"), std::string::npos);
  o.Clear();
  o.mutable_gravity()->set_z(-9.0);
  o.mutable_prior()->mutable_params()->set_mass(2.0);
  v1::Inertia* inertia = o.mutable_prior()->mutable_params()->mutable_inertia();
  inertia->set_ixx(0.01);
  inertia->set_iyy(0.02);
  inertia->set_izz(0.025);
  absl::StatusOr<inertia::InertiaOptions> ok = InertiaOptionsFromProto(o);
  ASSERT_TRUE(ok.ok()) << ok.status();
  EXPECT_EQ(ok->method, inertia::InertiaMethod::kConstrained);
  EXPECT_EQ(ok->gravity.z(), -9.0);
  ASSERT_TRUE(ok->prior.has_value());
  EXPECT_EQ(ok->prior->weight, 1.0);  // 0 = the default weight
  EXPECT_EQ(ok->prior->params.mass, 2.0);
}

}  // namespace
}  // namespace tactforce::api
