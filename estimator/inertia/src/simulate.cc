// Simulated inertia logs (simulate.h): the built-in objects and objects
// from parameters (a box with the same inertia, its mesh and contact points),
// the excitation trajectory, the wrench a wrist sensor measures or the
// fingertip forces the planner gives along it, and seeded noise.
#include "tactforce/inertia/simulate.h"

#include <cmath>
#include <random>

#include <Eigen/Eigenvalues>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "internal.h"
#include "tactforce/inertia/metrics.h"
#include "tactforce/inertia/samples.h"
#include "tactforce/planner/trajectory.h"
#include "tactforce/io/status_macros.h"

namespace tactforce::inertia {

using internal::ExpSO3;
using internal::Skew;

ExcitationTrajectory ExcitationTrajectory::Default() {
  ExcitationTrajectory e;
  e.position = {{0, 0.10, 0.31, 0.0}, {0, 0.05, 0.73, 1.1}, {1, 0.08, 0.23, 0.4},
                {1, 0.05, 0.61, 2.0}, {2, 0.10, 0.37, 0.8}, {2, 0.04, 0.83, 2.6}};
  e.orientation = {{0, 0.80, 0.19, 0.3}, {0, 0.30, 0.53, 1.7}, {1, 0.45, 0.29, 0.9},
                   {1, 0.20, 0.67, 2.3}, {2, 0.80, 0.41, 1.3}, {2, 0.30, 0.79, 0.5}};
  return e;
}

void ExcitationTrajectory::Evaluate(double t, Vec3* p, Vec3* v, Vec3* a, Eigen::Matrix3d* R,
                                    Vec3* w, Vec3* dw) const {
  Vec3 x = position_offset, dx = Vec3::Zero(), ddx = Vec3::Zero();
  for (const SinusoidComponent& c : position) {
    const double om = 2 * M_PI * c.frequency_hz, arg = om * t + c.phase;
    x(c.axis) += c.amplitude * std::sin(arg);
    dx(c.axis) += c.amplitude * om * std::cos(arg);
    ddx(c.axis) -= c.amplitude * om * om * std::sin(arg);
  }
  Vec3 q = orientation_offset, dq = Vec3::Zero(), ddq = Vec3::Zero();  // yaw, pitch, roll
  for (const SinusoidComponent& c : orientation) {
    const double om = 2 * M_PI * c.frequency_hz, arg = om * t + c.phase;
    q(c.axis) += c.amplitude * std::sin(arg);
    dq(c.axis) += c.amplitude * om * std::cos(arg);
    ddq(c.axis) -= c.amplitude * om * om * std::sin(arg);
  }
  const Vec3 e1 = Vec3::UnitZ(), e2 = Vec3::UnitY(), e3 = Vec3::UnitX();
  const Eigen::Matrix3d R1 = Eigen::AngleAxisd(q(0), e1).toRotationMatrix();
  const Eigen::Matrix3d R2 = Eigen::AngleAxisd(q(1), e2).toRotationMatrix();
  const Eigen::Matrix3d R3 = Eigen::AngleAxisd(q(2), e3).toRotationMatrix();
  const Eigen::Matrix3d A = R3.transpose() * R2.transpose();  // R3^T R2^T
  const Eigen::Matrix3d dA =
      -dq(2) * Skew(e3) * A - R3.transpose() * dq(1) * Skew(e2) * R2.transpose();
  const Eigen::Matrix3d dR3t = -dq(2) * Skew(e3) * R3.transpose();
  if (p) *p = x;
  if (v) *v = dx;
  if (a) *a = ddx;
  if (R) *R = R1 * R2 * R3;
  if (w) *w = A * e1 * dq(0) + R3.transpose() * e2 * dq(1) + e3 * dq(2);
  if (dw)
    *dw = A * e1 * ddq(0) + dA * e1 * dq(0) + R3.transpose() * e2 * ddq(1) + dR3t * e2 * dq(1) +
          e3 * ddq(2);
}

absl::StatusOr<SimulationNoise> NadeauNoise(const std::string& level) {
  SimulationNoise n;
  double k;
  if (level == "low")
    k = 0.5;
  else if (level == "moderate")
    k = 1.0;
  else if (level == "high")
    k = 2.0;
  else
    return absl::InvalidArgumentError(
        absl::StrCat("noise level: unknown '", level, "' (expected low, moderate or high)"));
  n.linear_acceleration_sigma = 0.05 * k;
  n.angular_acceleration_sigma = 0.5 * k;
  n.force_sigma = 0.1 * k;
  n.torque_sigma = 0.005 * k;
  return n;
}

std::vector<std::string> BuiltInObjectNames() { return {"seed-table1", "box"}; }

absl::StatusOr<SimulatedObject> ObjectFromParameters(const std::string& name,
                                                     const InertialParameters& p) {
  if (!(p.mass > 0) || !p.com.allFinite() || ScaledPseudoInertiaMinEigenvalue(p) <= 0) {
    return absl::InvalidArgumentError(absl::StrCat(
        "object '", name,
        "': parameters are not physically consistent (mass > 0 and a positive definite "
        "pseudo-inertia are required)"));
  }
  const Eigen::Matrix3d h = p.inertia_com.Matrix();
  const Eigen::Matrix3d sigma = 0.5 * h.trace() * Eigen::Matrix3d::Identity() - h;
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(sigma);
  Eigen::Matrix3d V = es.eigenvectors();  // ascending second moments
  if (V.determinant() < 0) V.col(2) = -V.col(2);
  const Vec3 half = (3.0 * es.eigenvalues() / p.mass).cwiseMax(0.0).cwiseSqrt();
  SimulatedObject o;
  o.name = name;
  o.params = p;
  for (int sx : {-1, 1})
    for (int sy : {-1, 1})
      for (int sz : {-1, 1})
        o.hull.push_back(p.com + V * Vec3(sx * half(0), sy * half(1), sz * half(2)));
  // The box as a closed mesh: corner index 4*(x>0) + 2*(y>0) + (z>0); each
  // face's two triangles counter-clockwise seen from outside (det V = +1).
  o.mesh.vertices = o.hull;
  o.mesh.triangles = {{0, 1, 3}, {0, 3, 2}, {4, 6, 7}, {4, 7, 5},   // -x, +x
                      {0, 4, 5}, {0, 5, 1}, {2, 3, 7}, {2, 7, 6},   // -y, +y
                      {0, 2, 6}, {0, 6, 4}, {1, 5, 7}, {1, 7, 3}};  // -z, +z
  // A pinch across the thinnest dimension: two fingertips on each of the two
  // largest faces, spread along the longest axis.
  const double s = 0.4 * half(2);
  const Vec3 thin = V.col(0), lng = V.col(2);
  const std::pair<int, int> pattern[] = {{+1, +1}, {-1, -1}, {-1, +1}, {+1, -1}};
  for (const auto& [side, along] : pattern) {
    o.contact_points.push_back(p.com + side * half(0) * thin + along * s * lng);
    o.contact_normals.push_back(-side * thin);
  }
  return o;
}

absl::StatusOr<SimulatedObject> BuiltInObject(const std::string& name) {
  InertialParameters p;
  if (name == "seed-table1") {
    p.mass = 1.3;
    p.com = Vec3(0.2, 0.5, 0.1);
    p.inertia_com =
        InertiaTensor::FromArray({40.15e-2, 12.92e-2, 47.99e-2, -12.97e-2, -2.59e-2, -6.49e-2});
  } else if (name == "box") {
    p.mass = 0.5;
    p.com = Vec3(0.02, -0.01, 0.03);
    const double a = 0.2, b = 0.1, c = 0.05;
    const Eigen::Matrix3d d =
        (p.mass / 12.0 * Vec3(b * b + c * c, a * a + c * c, a * a + b * b)).asDiagonal();
    const Eigen::Matrix3d R = Eigen::AngleAxisd(0.5, Vec3(1, 2, 3).normalized()).toRotationMatrix();
    p.inertia_com = InertiaTensor::FromMatrix(R * d * R.transpose());
  } else {
    return absl::InvalidArgumentError(
        absl::StrCat("object: unknown built-in '", name, "' (expected seed-table1 or box)"));
  }
  return ObjectFromParameters(name, p);
}

namespace {

void NoisyPose(std::mt19937_64& rng, const SimulationNoise& n, InertiaSample& s) {
  std::normal_distribution<double> N(0.0, 1.0);
  if (n.position_sigma > 0) s.position += n.position_sigma * Vec3(N(rng), N(rng), N(rng));
  if (n.orientation_sigma > 0) {
    const Vec3 e = n.orientation_sigma * Vec3(N(rng), N(rng), N(rng));
    s.orientation = Eigen::Quaterniond(s.orientation.toRotationMatrix() * ExpSO3(e));
    s.orientation.normalize();
  }
}

void NoisySample(std::mt19937_64& rng, const SimulationNoise& n, ForceSource src,
                 InertiaSample& s) {
  std::normal_distribution<double> N(0.0, 1.0);
  auto v3 = [&](double sigma) {
    return sigma > 0 ? Vec3(sigma * Vec3(N(rng), N(rng), N(rng))) : Vec3::Zero();
  };
  if (src == ForceSource::kWrench) {
    s.force += v3(n.force_sigma);
    s.torque += v3(n.torque_sigma);
  } else {
    for (ContactReading& c : s.contacts) c.force += v3(n.force_sigma);
  }
  NoisyPose(rng, n, s);
  if (s.kinematics) {
    s.kinematics->angular_velocity += v3(n.angular_velocity_sigma);
    s.kinematics->angular_acceleration += v3(n.angular_acceleration_sigma);
    s.kinematics->acceleration += v3(n.linear_acceleration_sigma);
  }
}

absl::Status ValidateSimulationOptions(const SimulationOptions& o) {
  if (!(o.rate_hz > 0) || !std::isfinite(o.rate_hz))
    return absl::InvalidArgumentError("rate_hz: must be > 0");
  if (!(o.duration > 0) || !std::isfinite(o.duration))
    return absl::InvalidArgumentError("duration: must be > 0");
  if (!o.gravity.allFinite()) return absl::InvalidArgumentError("gravity: not finite");
  const SimulationNoise& n = o.noise;
  for (double v :
       {n.force_sigma, n.torque_sigma, n.position_sigma, n.orientation_sigma,
        n.linear_acceleration_sigma, n.angular_acceleration_sigma, n.angular_velocity_sigma}) {
    if (!(v >= 0) || !std::isfinite(v))
      return absl::InvalidArgumentError("noise: sigmas must be finite and >= 0");
  }
  for (const auto* list : {&o.trajectory.position, &o.trajectory.orientation}) {
    for (const SinusoidComponent& c : *list) {
      if (c.axis < 0 || c.axis > 2)
        return absl::InvalidArgumentError("trajectory: axis must be 0, 1 or 2");
      if (!std::isfinite(c.amplitude) || !std::isfinite(c.frequency_hz) || !std::isfinite(c.phase))
        return absl::InvalidArgumentError("trajectory: components must be finite");
    }
  }
  return absl::OkStatus();
}

// In hand: the object and its fingertip contacts as a planner trajectory
// problem (the steps are added per sample).
planner::TrajectoryProblem InHandProblem(const SimulatedObject& object,
                                         const SimulationOptions& o) {
  const InertialParameters& p = object.params;
  planner::TrajectoryProblem traj;
  traj.base.object.mass = p.mass;
  traj.base.object.com = p.com;
  for (int i = 0; i < o.num_contacts; ++i) {
    planner::Contact c;
    c.name = absl::StrCat("c", i);
    c.position = object.contact_points[i];
    c.normal = object.contact_normals[i];
    c.friction = o.friction;
    c.min_normal_force = o.min_normal_force;
    traj.base.contacts.push_back(c);
  }
  planner::Inertia in;
  in.ixx = p.inertia_com.ixx, in.iyy = p.inertia_com.iyy, in.izz = p.inertia_com.izz;
  in.ixy = p.inertia_com.ixy, in.ixz = p.inertia_com.ixz, in.iyz = p.inertia_com.iyz;
  traj.inertia = in;
  return traj;
}

// The fingertip forces of every sample: one warm-started geometric plan per
// sample along the trajectory's steps.
absl::Status AddInHandForces(const planner::TrajectoryProblem& traj, const SimulatedObject& object,
                             const SimulationOptions& o, InertiaSamples* s) {
  planner::PlanOptions po;
  absl::StatusOr<planner::TrajectoryResult> r =
      planner::PlanTrajectory(traj, po, planner::SolverKind::kGeometric, /*warm_start=*/true);
  if (!r.ok())
    return absl::InvalidArgumentError(absl::StrCat("in-hand forces: ", r.status().message()));
  for (size_t k = 0; k < s->samples.size(); ++k) {
    const planner::PlanResult& pr = r->steps[k];
    if (pr.status != planner::PlanStatus::kOptimal) {
      return absl::InvalidArgumentError(
          absl::StrFormat("in-hand forces infeasible at t = %.4g s (%s): raise friction or "
                          "min_normal_force, or slow the "
                          "trajectory",
                          s->samples[k].t, pr.message));
    }
    for (int i = 0; i < o.num_contacts; ++i) {
      ContactReading c;
      c.point = object.contact_points[i];
      c.force = pr.forces[i];
      s->samples[k].contacts.push_back(c);
    }
  }
  return absl::OkStatus();
}

}  // namespace

void AddNoise(InertiaSamples& samples, const SimulationNoise& noise, uint64_t seed) {
  std::mt19937_64 rng(seed);
  for (InertiaSample& s : samples.samples) NoisySample(rng, noise, samples.source, s);
}

absl::StatusOr<SimulationResult> SimulateInertia(const SimulationOptions& o) {
  TF_RETURN_IF_ERROR(ValidateSimulationOptions(o));
  SimulatedObject object;
  if (o.custom) {
    object = *o.custom;
  } else {
    TF_ASSIGN_OR_RETURN(object, BuiltInObject(o.object));
  }
  const int steps = static_cast<int>(std::floor(o.duration * o.rate_hz + 1e-9)) + 1;
  if (steps < 5) return absl::InvalidArgumentError("duration * rate_hz: fewer than 5 samples");
  if (steps > 10'000'000)
    return absl::InvalidArgumentError("duration * rate_hz: more than 1e7 samples");
  const bool in_hand = o.mode == SimulationMode::kInHand;
  if (in_hand &&
      (o.num_contacts < 1 || o.num_contacts > static_cast<int>(object.contact_points.size()))) {
    return absl::InvalidArgumentError(
        absl::StrCat("num_contacts: must be 1..", object.contact_points.size()));
  }

  const InertialParameters& p = object.params;
  const Eigen::Matrix3d inertia_com = p.inertia_com.Matrix();
  SimulationResult out;
  out.object = object;
  out.truth.params = p;
  out.truth.gravity_world = o.gravity;
  InertiaSamples& s = out.samples;
  s.source = in_hand ? ForceSource::kContacts : ForceSource::kWrench;
  s.num_contacts = in_hand ? o.num_contacts : 0;
  s.source_name = absl::StrCat("simulated ", object.name);
  s.samples.resize(steps);

  planner::TrajectoryProblem traj;
  if (in_hand) traj = InHandProblem(object, o);
  for (int k = 0; k < steps; ++k) {
    const double t = k / o.rate_hz;
    Vec3 pos, vel, acc, w, dw;
    Eigen::Matrix3d R;
    o.trajectory.Evaluate(t, &pos, &vel, &acc, &R, &w, &dw);
    InertiaSample& x = s.samples[k];
    x.t = t;
    x.position = pos;
    x.orientation = Eigen::Quaterniond(R);
    x.orientation.normalize();
    if (o.write_kinematics) x.kinematics = MeasuredKinematics{w, vel, dw, acc};
    planner::TrajectoryStep step;
    step.gravity = R.transpose() * o.gravity;
    step.linear_acceleration = R.transpose() * acc;
    step.angular_velocity = w;
    step.angular_acceleration = dw;
    if (in_hand) {
      traj.steps.push_back(step);
    } else {
      planner::ObjectModel om;
      om.mass = p.mass;
      om.com = p.com;
      const planner::Wrench need = planner::RequiredContactWrench(om, inertia_com, step);
      x.force = need.force;
      x.torque = need.torque;
    }
  }
  if (in_hand) {
    TF_RETURN_IF_ERROR(AddInHandForces(traj, object, o, &s));
  }
  std::mt19937_64 rng(o.seed);
  for (InertiaSample& x : s.samples) NoisySample(rng, o.noise, s.source, x);
  return out;
}

absl::Status WriteSimulation(const SimulationResult& r, const std::string& csv_path,
                             const std::string& truth_path) {
  TF_RETURN_IF_ERROR(WriteInertiaCsvFile(r.samples, csv_path));
  return WriteTruthJsonFile(r.truth, truth_path);
}

}  // namespace tactforce::inertia
