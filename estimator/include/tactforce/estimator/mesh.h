// Triangle meshes (object frame, m): inline, or read from STL (ASCII or
// binary) and Wavefront OBJ. Used for contact normals and convex hulls.
#pragma once

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "absl/status/statusor.h"

namespace tactforce::estimator {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside
};

// Checks indices and degenerate (zero-area) triangles; errors name the
// triangle ("mesh.triangles[4]: ...").
absl::Status ValidateMesh(const TriangleMesh& mesh);

// Errors name the file and line (OBJ, ASCII STL) or the byte offset (binary STL).
absl::StatusOr<TriangleMesh> ReadMeshFile(const std::string& path);

struct NearestTriangle {
  int triangle = -1;
  double distance = 0.0;         // m
  Eigen::Vector3d closest;       // closest point on the mesh
  Eigen::Vector3d inward_normal; // unit, pointing INTO the object
};

// Nearest triangle to `point` (brute force; meshes here are small).
NearestTriangle FindNearestTriangle(const TriangleMesh& mesh, const Eigen::Vector3d& point);

}  // namespace tactforce::estimator
