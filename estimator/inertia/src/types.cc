// The inertial parameter types (types.h): the inertia tensor as a matrix and
// an array, and the standard parameters [m, m c, I about the origin] and back.
#include "tactforce/inertia/types.h"

namespace tactforce::inertia {

Eigen::Matrix3d InertiaTensor::Matrix() const {
  Eigen::Matrix3d m;
  m << ixx, ixy, ixz, ixy, iyy, iyz, ixz, iyz, izz;
  return m;
}

InertiaTensor InertiaTensor::FromMatrix(const Eigen::Matrix3d& m) {
  InertiaTensor t;
  t.ixx = m(0, 0);
  t.iyy = m(1, 1);
  t.izz = m(2, 2);
  t.ixy = 0.5 * (m(0, 1) + m(1, 0));
  t.ixz = 0.5 * (m(0, 2) + m(2, 0));
  t.iyz = 0.5 * (m(1, 2) + m(2, 1));
  return t;
}

InertiaTensor InertiaTensor::FromArray(const std::array<double, 6>& a) {
  InertiaTensor t;
  t.ixx = a[0];
  t.iyy = a[1];
  t.izz = a[2];
  t.ixy = a[3];
  t.ixz = a[4];
  t.iyz = a[5];
  return t;
}

Eigen::Matrix3d InertialParameters::InertiaOrigin() const {
  return inertia_com.Matrix() +
         mass * (com.squaredNorm() * Eigen::Matrix3d::Identity() - com * com.transpose());
}

Vector10d InertialParameters::ToStandard() const {
  const Eigen::Matrix3d io = InertiaOrigin();
  Vector10d pi;
  pi << mass, mass * com.x(), mass * com.y(), mass * com.z(), io(0, 0), io(1, 1), io(2, 2),
      io(0, 1), io(0, 2), io(1, 2);
  return pi;
}

InertialParameters InertialParameters::FromStandard(const Vector10d& pi) {
  InertialParameters p;
  p.mass = pi(0);
  const Vec3 h = pi.segment<3>(1);
  Eigen::Matrix3d io;
  io << pi(4), pi(7), pi(8), pi(7), pi(5), pi(9), pi(8), pi(9), pi(6);
  if (p.mass != 0.0) {
    p.com = h / p.mass;
    // I_c = I_o - m (|c|^2 I - c c^T) = I_o - (|h|^2 I - h h^T) / m
    io -= (h.squaredNorm() * Eigen::Matrix3d::Identity() - h * h.transpose()) / p.mass;
  }
  p.inertia_com = InertiaTensor::FromMatrix(io);
  return p;
}

const std::array<const char*, 10>& StandardParameterNames() {
  static const std::array<const char*, 10> names = {"m",   "m*cx", "m*cy", "m*cz", "Ixx",
                                                    "Iyy", "Izz",  "Ixy",  "Ixz",  "Iyz"};
  return names;
}

}  // namespace tactforce::inertia
