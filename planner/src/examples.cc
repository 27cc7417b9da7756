// The built-in example grasps of examples.h.
#include "tactforce/planner/examples.h"

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

namespace tactforce::planner {
namespace {

Contact Finger(std::string name, const Vec3& position, const Vec3& normal, double mu, double sigma,
               double min_force) {
  Contact c;
  c.name = std::move(name);
  c.position = position;
  c.normal = normal.normalized();
  c.friction = mu;
  c.kind = ContactKind::kIntrinsic;
  c.sigma = sigma;
  c.min_normal_force = min_force;
  return c;
}

}  // namespace

std::vector<ExampleGrasp> BuiltInGrasps() {
  std::vector<ExampleGrasp> out;

  {  // Sphere, radius 3.5 cm, pinched along x; gravity along -z.
    ExampleGrasp g;
    g.name = "sphere-pinch";
    g.description = "2-finger pinch of a 0.082 kg sphere (r 35 mm), mu 0.8, sigma 0.3 N";
    g.problem.object.mass = 0.082;
    const double r = 0.035;
    g.problem.contacts = {Finger("thumb", {-r, 0, 0}, {1, 0, 0}, 0.8, 0.3, 0.2),
                          Finger("index", {r, 0, 0}, {-1, 0, 0}, 0.8, 0.3, 0.2)};
    out.push_back(std::move(g));
  }
  {  // Wrench handle along x (24 mm wide); CoM 1 cm towards the head.
    ExampleGrasp g;
    g.name = "wrench-3f";
    g.description = "3-finger grasp of a 0.3 kg wrench handle, mu 0.9, sigma 0.5 N";
    g.problem.object.mass = 0.3;
    g.problem.object.com = Vec3(0.01, 0, 0);
    const double w = 0.012;
    g.problem.contacts = {Finger("index", {0.02, w, 0}, {0, -1, 0}, 0.9, 0.5, 0.3),
                          Finger("middle", {-0.02, w, 0}, {0, -1, 0}, 0.9, 0.5, 0.3),
                          Finger("thumb", {0.0, -w, 0}, {0, 1, 0}, 0.9, 0.5, 0.3)};
    out.push_back(std::move(g));
  }
  {  // Upright cylinder, diameter 0.11 m, four fingers 90 degrees apart.
    ExampleGrasp g;
    g.name = "cylinder-4f";
    g.description = "4-finger grasp of a 0.36 kg cylinder (diameter 0.11 m), mu 0.6, sigma 0.3 N";
    g.problem.object.mass = 0.36;
    const double r = 0.055;
    const char* names[] = {"thumb", "index", "middle", "ring"};
    for (int i = 0; i < 4; ++i) {
      const double a = i * std::numbers::pi / 2;
      const Vec3 radial(std::cos(a), std::sin(a), 0);
      g.problem.contacts.push_back(Finger(names[i], r * radial, -radial, 0.6, 0.3, 0.3));
    }
    out.push_back(std::move(g));
  }
  return out;
}

TrajectoryProblem WrenchLiftAndRotate(int steps) {
  TrajectoryProblem t;
  for (const ExampleGrasp& g : BuiltInGrasps()) {
    if (g.name == "wrench-3f") t.base = g.problem;
  }
  t.inertia = Inertia{4e-4, 2.5e-3, 2.7e-3, 1e-5, -2e-5, 0};
  const double duration = 2.0, amplitude = 0.6, w0 = std::numbers::pi / duration;
  for (int k = 0; k < steps; ++k) {
    const double s = steps > 1 ? duration * k / (steps - 1) : 0.0;
    const double angle = amplitude * (1 - std::cos(w0 * s)) / 2;
    TrajectoryStep step;
    const Eigen::Matrix3d world_from_object =
        Eigen::AngleAxisd(angle, Vec3::UnitX()).toRotationMatrix();
    step.gravity = world_from_object.transpose() * Vec3(0, 0, -9.81);
    step.linear_acceleration =
        world_from_object.transpose() * Vec3(0, 0, 0.5 * std::sin(2 * w0 * s));
    step.angular_velocity = Vec3(amplitude * w0 * std::sin(w0 * s) / 2, 0, 0);
    step.angular_acceleration = Vec3(amplitude * w0 * w0 * std::cos(w0 * s) / 2, 0, 0);
    t.steps.push_back(step);
  }
  return t;
}

}  // namespace tactforce::planner
