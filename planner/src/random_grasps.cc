// MakeRandomGrasp() (random_grasps.h): seeded random grasps on spheres, boxes, cylinders.
#include "tactforce/planner/random_grasps.h"

#include <cmath>
#include <numbers>

namespace tactforce::planner {
namespace {

struct Sampler {
  std::mt19937_64& rng;
  double Uniform(double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  }
  int Int(int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); }
  bool Chance(double p) { return Uniform(0, 1) < p; }
  Vec3 UnitVector() {
    std::normal_distribution<double> g;
    Vec3 v(g(rng), g(rng), g(rng));
    while (v.norm() < 1e-6) v = Vec3(g(rng), g(rng), g(rng));
    return v.normalized();
  }
};

// A point on the surface and the inward normal there.
struct SurfacePoint {
  Vec3 position, normal;
};

SurfacePoint OnSphere(Sampler& s, double radius) {
  const Vec3 u = s.UnitVector();
  return {radius * u, -u};
}

SurfacePoint OnBox(Sampler& s, const Vec3& half) {
  const int axis = s.Int(0, 2);
  const double sign = s.Chance(0.5) ? 1.0 : -1.0;
  Vec3 p(s.Uniform(-half.x(), half.x()), s.Uniform(-half.y(), half.y()),
         s.Uniform(-half.z(), half.z()));
  p(axis) = sign * half(axis);
  return {p, -sign * Vec3::Unit(axis)};
}

SurfacePoint OnCylinder(Sampler& s, double radius, double half_height) {
  if (s.Chance(0.75)) {  // side
    const double a = s.Uniform(0, 2 * std::numbers::pi);
    const Vec3 radial(std::cos(a), std::sin(a), 0);
    return {radius * radial + Vec3(0, 0, s.Uniform(-half_height, half_height)), -radial};
  }
  const double sign = s.Chance(0.5) ? 1.0 : -1.0;
  const double a = s.Uniform(0, 2 * std::numbers::pi);
  const double r = radius * std::sqrt(s.Uniform(0, 1));
  return {Vec3(r * std::cos(a), r * std::sin(a), sign * half_height), Vec3(0, 0, -sign)};
}

}  // namespace

RandomGrasp MakeRandomGrasp(std::mt19937_64& rng, const RandomGraspOptions& o) {
  Sampler s{rng};
  RandomGrasp out;
  PlanProblem& p = out.problem;
  p.object.mass = s.Uniform(o.min_mass, o.max_mass);
  p.object.gravity = 9.81 * s.UnitVector();
  const int n = s.Int(o.min_contacts, o.max_contacts);
  const int shape = s.Int(0, 2);
  const double size = s.Uniform(0.02, 0.08);
  const Vec3 half(s.Uniform(0.02, 0.08), s.Uniform(0.02, 0.08), s.Uniform(0.02, 0.08));
  const double half_height = s.Uniform(0.02, 0.1);
  // CoM well inside the object.
  const Vec3 extent = shape == 0 ? Vec3::Constant(size / std::sqrt(3.0))
                      : shape == 1
                          ? half
                          : Vec3(size / std::sqrt(2.0), size / std::sqrt(2.0), half_height);
  p.object.com =
      0.5 * extent.cwiseProduct(Vec3(s.Uniform(-1, 1), s.Uniform(-1, 1), s.Uniform(-1, 1)));

  for (int i = 0; i < n; ++i) {
    SurfacePoint sp = shape == 0   ? OnSphere(s, size)
                      : shape == 1 ? OnBox(s, half)
                                   : OnCylinder(s, size, half_height);
    Contact c;
    c.name = "c" + std::to_string(i);
    c.position = sp.position;
    c.normal = sp.normal;
    c.friction = s.Uniform(o.min_friction, o.max_friction);
    c.kind = s.Chance(o.extrinsic_probability) ? ContactKind::kExtrinsic : ContactKind::kIntrinsic;
    c.sigma = c.kind == ContactKind::kIntrinsic ? s.Uniform(0, o.max_sigma) : 0.0;
    c.min_normal_force = s.Uniform(0, o.max_min_force);
    if (s.Chance(0.2)) c.max_normal_force = c.min_normal_force + s.Uniform(2.0, 30.0);
    p.contacts.push_back(c);
  }

  // Two point contacts cannot resist a torque about the line through them,
  // so a pinch is only feasible with the CoM on that line: make most
  // 2-contact grasps such pinches (mirrored contact, CoM on the axis).
  if (n == 2 && s.Chance(0.8)) {
    Contact& second = p.contacts[1];
    second.position = -p.contacts[0].position;
    second.normal = -p.contacts[0].normal;
    p.object.com = s.Uniform(-0.5, 0.5) * p.contacts[0].position;
  }

  if (s.Chance(o.infeasible_fraction)) {
    out.infeasible_by_construction = true;
    if (s.Chance(0.5)) {
      // Frictionless fingers on a horizontal ring cannot lift the weight.
      p.object.gravity = Vec3(0, 0, -9.81);
      for (int i = 0; i < n; ++i) {
        const double a = 2 * std::numbers::pi * i / n + s.Uniform(-0.2, 0.2);
        const Vec3 radial(std::cos(a), std::sin(a), 0);
        p.contacts[i].position = size * radial;
        p.contacts[i].normal = -radial;
        p.contacts[i].friction = 0.0;
      }
    } else {
      // An antipodal pair cannot resist a torque about its own axis.
      p.contacts.resize(2);
      const Vec3 axis = s.UnitVector();
      p.contacts[0].position = size * axis;
      p.contacts[0].normal = -axis;
      p.contacts[1].position = -size * axis;
      p.contacts[1].normal = axis;
      p.object.com = Vec3::Zero();
      p.external_wrench.torque = s.Uniform(0.05, 0.5) * axis;
    }
  }
  return out;
}

}  // namespace tactforce::planner
