// The cross-product matrix of a 3-vector: Skew(v) * u == v.cross(u).
// Shared by the planner (wrench maps, the parameter regressor) and the
// inertia estimator (kinematics).
#pragma once

#include <Eigen/Core>

namespace tactforce::planner {

inline Eigen::Matrix3d Skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

}  // namespace tactforce::planner
