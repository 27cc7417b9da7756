#include "tactforce/inertia/simulate.h"

#include <cmath>
#include <cstdio>
#include <string>

#include <gtest/gtest.h>

#include "tactforce/inertia/hull.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/samples.h"
#include "test_util.h"

namespace tactforce::inertia {
namespace {

using testing::ShortSimulation;

TEST(InertiaSimulate, SeedTable1IsThePaperObject) {
  absl::StatusOr<SimulatedObject> o = BuiltInObject("seed-table1");
  ASSERT_TRUE(o.ok());
  EXPECT_EQ(o->params.mass, 1.3);
  EXPECT_EQ(o->params.com, Vec3(0.2, 0.5, 0.1));
  EXPECT_DOUBLE_EQ(o->params.inertia_com.ixy, -12.97e-2);
  EXPECT_DOUBLE_EQ(o->params.inertia_com.izz, 47.99e-2);
  EXPECT_TRUE(IsPhysicallyConsistent(o->params));
  ASSERT_EQ(o->contact_points.size(), 4u);
  absl::StatusOr<ConvexHull> hull = ComputeConvexHull(o->hull);
  ASSERT_TRUE(hull.ok());
  EXPECT_TRUE(hull->Contains(o->params.com));
  for (size_t i = 0; i < 4; ++i) {
    EXPECT_TRUE(hull->Contains(o->contact_points[i], 1e-9));  // on the surface
    EXPECT_FALSE(hull->Contains(o->contact_points[i] - 1e-3 * o->contact_normals[i], 1e-9));
  }
  EXPECT_FALSE(BuiltInObject("teapot").ok());
}

TEST(InertiaSimulate, DeterministicForASeed) {
  SimulationOptions o = ShortSimulation("box", SimulationMode::kInHand, false);
  o.noise.force_sigma = 0.3;
  o.noise.position_sigma = 1e-4;
  const std::string a = InertiaSamplesToCsv(SimulateInertia(o)->samples);
  const std::string b = InertiaSamplesToCsv(SimulateInertia(o)->samples);
  EXPECT_EQ(a, b);
  o.seed += 1;
  EXPECT_NE(a, InertiaSamplesToCsv(SimulateInertia(o)->samples));
}

TEST(InertiaSimulate, AnalyticKinematicsMatchFiniteDifferences) {
  const ExcitationTrajectory e = ExcitationTrajectory::Default();
  const double h = 1e-5;
  for (double t : {0.0, 1.3, 4.7}) {
    Vec3 p0, v0, a0, w0, dw0, pp, vp, ap, wp, dwp, pm, vm, am, wm, dwm;
    Eigen::Matrix3d R0, Rp, Rm;
    e.Evaluate(t, &p0, &v0, &a0, &R0, &w0, &dw0);
    e.Evaluate(t + h, &pp, &vp, &ap, &Rp, &wp, &dwp);
    e.Evaluate(t - h, &pm, &vm, &am, &Rm, &wm, &dwm);
    EXPECT_LT(((pp - pm) / (2 * h) - v0).norm(), 1e-6);
    EXPECT_LT(((vp - vm) / (2 * h) - a0).norm(), 1e-6);
    EXPECT_LT(((wp - wm) / (2 * h) - dw0).norm(), 1e-5);
    // Body angular velocity: R^T dR/dt = [w].
    const Eigen::Matrix3d W = R0.transpose() * (Rp - Rm) / (2 * h);
    EXPECT_LT((Vec3(W(2, 1), W(0, 2), W(1, 0)) - w0).norm(), 1e-6);
  }
}

TEST(InertiaSimulate, InHandForcesArePlausibleAndBalanceTheMotion) {
  SimulationOptions o = ShortSimulation("seed-table1", SimulationMode::kInHand, true);
  absl::StatusOr<SimulationResult> sim = SimulateInertia(o);
  ASSERT_TRUE(sim.ok()) << sim.status();
  const InertialParameters& p = sim->truth.params;
  const Eigen::Matrix3d Io = p.InertiaOrigin();
  double max_err = 0, max_force = 0;
  for (const InertiaSample& s : sim->samples.samples) {
    const MeasuredKinematics& k = *s.kinematics;
    const Eigen::Matrix3d R = s.orientation.toRotationMatrix();
    const Vec3 amg = R.transpose() * (k.acceleration - o.gravity);
    const Vec3 w = k.angular_velocity, dw = k.angular_acceleration;
    const Vec3 F = p.mass * (amg + dw.cross(p.com) + w.cross(w.cross(p.com)));
    const Vec3 T = Io * dw + w.cross(Io * w) + p.mass * p.com.cross(amg);
    Vec3 f = Vec3::Zero(), tau = Vec3::Zero();
    for (size_t i = 0; i < s.contacts.size(); ++i) {
      const ContactReading& c = s.contacts[i];
      f += c.force;
      tau += c.point.cross(c.force);
      const Vec3 n = sim->object.contact_normals[i];
      const double fn = c.force.dot(n);
      EXPECT_GE(fn, o.min_normal_force - 1e-6);
      EXPECT_LE((c.force - fn * n).norm(), o.friction * fn + 1e-6);
      max_force = std::max(max_force, c.force.norm());
    }
    max_err = std::max({max_err, (f - F).norm(), (tau - T).norm()});
  }
  EXPECT_LT(max_err, 1e-6 * std::max(1.0, max_force));
  EXPECT_LT(max_force, 200.0);  // plausible fingertip forces
}

TEST(InertiaSimulate, NoiseHasTheRequestedSpread) {
  SimulationOptions clean = ShortSimulation("box", SimulationMode::kWristWrench, true);
  SimulationOptions noisy = clean;
  noisy.noise.force_sigma = 0.2;
  noisy.noise.torque_sigma = 0.01;
  noisy.noise.angular_acceleration_sigma = 0.5;
  const InertiaSamples a = SimulateInertia(clean)->samples, b = SimulateInertia(noisy)->samples;
  double sf = 0, st = 0, sa = 0;
  const int n = static_cast<int>(a.samples.size());
  for (int i = 0; i < n; ++i) {
    sf += (b.samples[i].force - a.samples[i].force).squaredNorm();
    st += (b.samples[i].torque - a.samples[i].torque).squaredNorm();
    sa += (b.samples[i].kinematics->angular_acceleration -
           a.samples[i].kinematics->angular_acceleration)
              .squaredNorm();
    EXPECT_EQ(a.samples[i].position, b.samples[i].position);
  }
  EXPECT_NEAR(std::sqrt(sf / (3 * n)), 0.2, 0.02);
  EXPECT_NEAR(std::sqrt(st / (3 * n)), 0.01, 0.001);
  EXPECT_NEAR(std::sqrt(sa / (3 * n)), 0.5, 0.05);
  // AddNoise on existing samples (e.g. the shared tools), Nadeau levels.
  InertiaSamples c = a;
  AddNoise(c, *NadeauNoise("moderate"), 5);
  double s2 = 0;
  for (int i = 0; i < n; ++i) s2 += (c.samples[i].force - a.samples[i].force).squaredNorm();
  EXPECT_NEAR(std::sqrt(s2 / (3 * n)), 0.1, 0.01);
  EXPECT_FALSE(NadeauNoise("extreme").ok());
}

TEST(InertiaSimulate, WritesCsvAndTruth) {
  absl::StatusOr<SimulationResult> sim =
      SimulateInertia(ShortSimulation("box", SimulationMode::kWristWrench, true));
  ASSERT_TRUE(sim.ok());
  const std::string dir = ::testing::TempDir();
  const std::string csv = dir + "/inertia_sim.csv", truth = dir + "/inertia_sim.truth.json";
  ASSERT_TRUE(WriteSimulation(*sim, csv, truth).ok());
  absl::StatusOr<InertiaSamples> s = ReadInertiaCsvFile(csv);
  ASSERT_TRUE(s.ok()) << s.status();
  EXPECT_EQ(s->samples.size(), sim->samples.samples.size());
  EXPECT_TRUE(s->HasKinematics());
  absl::StatusOr<InertiaTruth> t = ReadTruthJsonFile(truth);
  ASSERT_TRUE(t.ok()) << t.status();
  EXPECT_EQ(t->params.mass, sim->truth.params.mass);
  EXPECT_EQ(t->params.inertia_com.ixz, sim->truth.params.inertia_com.ixz);
  EXPECT_EQ(*t->gravity_world, Vec3(0, 0, -9.81));
  std::remove(csv.c_str());
  std::remove(truth.c_str());
}

TEST(InertiaSimulate, BadOptionsAreNamed) {
  SimulationOptions o = ShortSimulation("box", SimulationMode::kInHand, false);
  o.rate_hz = 0;
  EXPECT_NE(SimulateInertia(o).status().message().find("rate_hz"), std::string::npos);
  o = ShortSimulation("box", SimulationMode::kInHand, false);
  o.num_contacts = 7;
  EXPECT_NE(SimulateInertia(o).status().message().find("num_contacts"), std::string::npos);
  InertialParameters bad;
  bad.mass = 1;
  bad.inertia_com = InertiaTensor::FromArray({0.01, 0.01, 0.05, 0, 0, 0});
  EXPECT_FALSE(ObjectFromParameters("bad", bad).ok());
}

}  // namespace
}  // namespace tactforce::inertia
