#include "tactforce/inertia/samples.h"

#include <string>

#include <gtest/gtest.h>

#include "tactforce/inertia/fit.h"
#include "tactforce/inertia/simulate.h"
#include "test_util.h"

namespace tactforce::inertia {
namespace {

const char* kHeader = "t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz\n";

std::string Row(double t, double qw = 1, const std::string& fy = "0") {
  return std::to_string(t) + ",0,0,0," + std::to_string(qw) + ",0,0,0,0," + fy + ",1,0,0,0\n";
}

std::string Message(const std::string& csv) {
  absl::StatusOr<InertiaSamples> s = ParseInertiaCsv(csv, "run.csv");
  EXPECT_FALSE(s.ok());
  if (s.ok()) return "";
  EXPECT_EQ(s.status().code(), absl::StatusCode::kInvalidArgument);
  return std::string(s.status().message());
}

// Found by the csv fuzzer: std::stoi threw (and terminated) on this column.
TEST(InertiaCsv, ContactIndexPastTheLimitIsNamed) {
  EXPECT_EQ(Message("t,px,py,pz,qw,qx,qy,qz,c99999999999_px\n0,0,0,0,1,0,0,0,0\n"),
            "run.csv: column 'c99999999999_px': contact index out of range (0..9999)");
}

TEST(InertiaCsv, ParsesAWrenchFile) {
  std::string csv = kHeader;
  for (int i = 0; i < 5; ++i) csv += Row(0.01 * i, 2.0);  // non-unit quaternion: normalised
  absl::StatusOr<InertiaSamples> s = ParseInertiaCsv(csv, "run.csv");
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->source, ForceSource::kWrench);
  ASSERT_EQ(s->samples.size(), 5u);
  EXPECT_NEAR(s->samples[3].orientation.norm(), 1.0, 1e-15);
  EXPECT_EQ(s->samples[2].force.z(), 1.0);
  EXPECT_FALSE(s->HasKinematics());
  EXPECT_EQ(s->line_numbers[0], 2);
}

TEST(InertiaCsv, MissingColumnsAreNamed) {
  EXPECT_NE(Message("t,px,py,pz,qw,qx,qy,fx,fy,fz,tx,ty,tz\n0,0,0,0,1,0,0,0,0,0,0,0,0\n")
                .find("missing column(s) qz"),
            std::string::npos);
  const std::string m = Message("t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx\n0,0,0,0,1,0,0,0,0,0,0,0\n");
  EXPECT_NE(m.find("run.csv: missing column(s) ty, tz"), std::string::npos) << m;
  EXPECT_NE(Message("t,px,py,pz,qw,qx,qy,qz\n0,0,0,0,1,0,0,0\n").find("missing force columns"),
            std::string::npos);
  // Incomplete measured kinematics.
  std::string k = "t,px,py,pz,qw,qx,qy,qz,fx,fy,fz,tx,ty,tz,wx,wy,wz,dwx,dwy,dwz,ax,ay\n";
  const std::string km = Message(k + "0,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n");
  EXPECT_NE(km.find("incomplete measured kinematics: missing column(s) az"), std::string::npos)
      << km;
}

TEST(InertiaCsv, NonMonotonicAndDuplicateTimeNameTheLine) {
  std::string csv =
      std::string(kHeader) + Row(0.0) + Row(0.01) + Row(0.005) + Row(0.02) + Row(0.03);
  const std::string m = Message(csv);
  EXPECT_NE(m.find("run.csv:4: column 't'"), std::string::npos) << m;
  EXPECT_NE(m.find("before"), std::string::npos) << m;
  std::string dup = std::string(kHeader) + Row(0.0) + Row(0.01) + Row(0.02) + Row(0.02) + Row(0.03);
  const std::string d = Message(dup);
  EXPECT_NE(d.find("run.csv:5: column 't'"), std::string::npos) << d;
  EXPECT_NE(d.find("duplicates"), std::string::npos) << d;
}

TEST(InertiaCsv, TooFewSamplesSaysHowManyAreNeeded) {
  std::string csv = std::string(kHeader) + Row(0.0) + Row(0.01) + Row(0.02);
  const std::string m = Message(csv);
  EXPECT_NE(m.find("3 sample(s), at least 4 needed"), std::string::npos) << m;
  // FitInertia checks per method: CONSTRAINED from poses needs 5.
  csv += Row(0.03);
  absl::StatusOr<InertiaSamples> s = ParseInertiaCsv(csv, "run.csv");
  ASSERT_TRUE(s.ok()) << s.status();
  absl::StatusOr<InertiaFit> f = FitInertia(*s, InertiaOptions{});
  ASSERT_FALSE(f.ok());
  EXPECT_NE(f.status().message().find("4 sample(s), at least 5 needed by constrained"),
            std::string::npos)
      << f.status();
}

TEST(InertiaCsv, NanIsRejectedWithLineAndColumn) {
  std::string csv =
      std::string(kHeader) + Row(0.0) + Row(0.01) + Row(0.02, 1, "nan") + Row(0.03) + Row(0.04);
  const std::string m = Message(csv);
  EXPECT_NE(m.find("run.csv:4: column 'fy'"), std::string::npos) << m;
}

TEST(InertiaCsv, NearZeroQuaternionIsRejected) {
  std::string csv =
      std::string(kHeader) + Row(0.0) + Row(0.01) + Row(0.02) + Row(0.03, 1e-9) + Row(0.04);
  const std::string m = Message(csv);
  EXPECT_NE(m.find("run.csv:5: columns 'qw,qx,qy,qz'"), std::string::npos) << m;
  EXPECT_NE(m.find("near zero"), std::string::npos) << m;
}

TEST(InertiaCsv, ContactColumnSets) {
  const std::string pose = "t,px,py,pz,qw,qx,qy,qz";
  const std::string c0 = ",c0_px,c0_py,c0_pz,c0_fx,c0_fy,c0_fz";
  std::string m = Message(pose + c0 + ",c1_px\n0,0,0,0,1,0,0,0,0,0,0,0,0,0,0\n");
  EXPECT_NE(m.find("contact 1: missing column(s) c1_py, c1_pz, c1_fx, c1_fy, c1_fz"),
            std::string::npos)
      << m;
  m = Message(pose + c0 +
              ",c2_px,c2_py,c2_pz,c2_fx,c2_fy,c2_fz\n0,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n");
  EXPECT_NE(m.find("contact 1 has no columns"), std::string::npos) << m;
  m = Message(pose + c0 + ",fx,fy,fz,tx,ty,tz\n0,0,0,0,1,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0\n");
  EXPECT_NE(m.find("both wrench columns"), std::string::npos) << m;
}

TEST(InertiaSamples, ValidationNamesFields) {
  InertiaSamples s;
  s.source = ForceSource::kContacts;
  s.num_contacts = 2;
  for (int i = 0; i < 5; ++i) {
    InertiaSample x;
    x.t = 0.01 * i;
    x.contacts.resize(2);
    s.samples.push_back(x);
  }
  EXPECT_TRUE(ValidateInertiaSamples(s).ok());
  s.samples[2].orientation.coeffs().setZero();
  EXPECT_NE(ValidateInertiaSamples(s).message().find("samples[2].orientation: quaternion norm 0"),
            std::string::npos);
  s.samples[2].orientation.setIdentity();
  s.samples[3].contacts[1].force.x() = std::nan("");
  EXPECT_NE(ValidateInertiaSamples(s).message().find("samples[3].contacts[1].force: not finite"),
            std::string::npos);
  s.samples[3].contacts[1].force.setZero();
  s.samples[4].contacts.pop_back();
  EXPECT_NE(ValidateInertiaSamples(s).message().find("samples[4]: 1 contacts, expected 2"),
            std::string::npos);
}

TEST(InertiaCsv, SimulatedRoundTrip) {
  for (bool kin : {false, true}) {
    absl::StatusOr<SimulationResult> sim =
        SimulateInertia(testing::ShortSimulation("box", SimulationMode::kInHand, kin));
    ASSERT_TRUE(sim.ok()) << sim.status();
    const std::string csv = InertiaSamplesToCsv(sim->samples);
    absl::StatusOr<InertiaSamples> back = ParseInertiaCsv(csv, "sim.csv");
    ASSERT_TRUE(back.ok()) << back.status();
    ASSERT_EQ(back->samples.size(), sim->samples.samples.size());
    EXPECT_EQ(back->source, ForceSource::kContacts);
    EXPECT_EQ(back->num_contacts, 4);
    EXPECT_EQ(back->HasKinematics(), kin);
    for (size_t i = 0; i < back->samples.size(); i += 37) {
      const InertiaSample &a = sim->samples.samples[i], &b = back->samples[i];
      EXPECT_EQ(a.t, b.t);
      EXPECT_EQ(a.position, b.position);
      EXPECT_NEAR((a.orientation.coeffs() - b.orientation.coeffs()).norm(), 0.0, 1e-15);
      EXPECT_EQ(a.contacts[3].force, b.contacts[3].force);
      if (kin) {
        EXPECT_EQ(a.kinematics->angular_acceleration, b.kinematics->angular_acceleration);
      }
    }
  }
}

}  // namespace
}  // namespace tactforce::inertia
