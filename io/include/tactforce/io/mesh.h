// Triangle meshes: reading (STL ASCII/binary, OBJ, PLY ASCII/binary, through
// Debian's assimp), placing a CAD mesh in the object frame, and checking that
// a mesh bounds a solid. Used for contact normals, convex hulls and the
// density fits of the inertia library.
//
// Units and frames: a mesh read from a file is in the file's units and frame;
// `TransformToObjectFrame` maps it to the object frame in metres.
#pragma once

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tactforce::io {

struct TriangleMesh {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;  // counter-clockwise seen from outside
  // Optional colour per triangle (0xRRGGBB), from per-face or per-vertex
  // colours in the file; empty when the file has none.
  std::vector<uint32_t> face_colors;
};

// Checks indices and degenerate (zero-area) triangles; errors name the
// triangle ("mesh.triangles[4]: ...").
absl::Status ValidateMesh(const TriangleMesh& mesh);

// Limits of a mesh read by ReadMeshBytes/ReadMeshFile (meshes arrive in
// requests, so they bound what a request can make the server allocate):
// at most kMaxMeshVertices distinct vertices (after welding) and
// kMaxMeshTriangles triangles (after triangulation). A PLY header is checked
// before anything is read: each element (vertex, face or any other) may
// declare at most kMaxMeshVertices vertices / kMaxMeshTriangles items, and no
// more than the bytes after the header can hold.
inline constexpr int64_t kMaxMeshVertices = 2'000'000;
inline constexpr int64_t kMaxMeshTriangles = 4'000'000;

// Reads STL (ASCII or binary), Wavefront OBJ or PLY (ASCII or binary) with
// assimp; the format comes from the file's contents/extension. Polygons are
// triangulated; vertices at identical positions are merged, so shared edges
// are shared indices. Errors name the file ("Hammer.ply: ..."): bad or
// oversized input is InvalidArgument, running out of memory ResourceExhausted;
// no exception escapes.
absl::StatusOr<TriangleMesh> ReadMeshFile(const std::string& path);

// The same from memory. `format` is "stl", "obj" or "ply" (case-insensitive);
// `name` is used in messages (e.g. "mesh" or the original file name). Only
// `bytes` are read: files the mesh refers to (an OBJ's `mtllib`) are never
// opened, so request data cannot make the caller touch its file system.
absl::StatusOr<TriangleMesh> ReadMeshBytes(std::string_view bytes, std::string_view format,
                                           std::string_view name);

// Mesh format from a file name's extension ("stl", "obj", "ply"), or
// InvalidArgument naming the file and the accepted extensions.
absl::StatusOr<std::string> MeshFormatFromPath(const std::string& path);

// Where a mesh sits: its unit scale and the pose of the OBJECT frame in the
// MESH frame (position in metres, after scaling). A mesh vertex v maps to
// the object frame as R^T (scale v - position), R = orientation.
struct MeshPlacement {
  double scale = 1.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  // w, x, y, z
};

// scale finite and > 0, position finite, quaternion finite with norm >= 1e-6
// (normalised by TransformToObjectFrame). Errors start with `field`
// (e.g. "mesh.scale: must be > 0 (got -1)").
absl::Status ValidatePlacement(const MeshPlacement& placement, std::string_view field = "mesh");

// The mesh in the object frame, metres (vertices mapped as above; the
// quaternion is normalised; triangles and colours unchanged).
TriangleMesh TransformToObjectFrame(const TriangleMesh& mesh, const MeshPlacement& placement);

// A mesh descriptor JSON:
//   {"mesh": "Hammer.ply", "scale": 0.001,
//    "object_in_mesh": {"position": [x, y, z], "quaternion": [w, x, y, z]}}
// "mesh" is required, the others optional (defaults 1, origin, identity);
// unknown keys are errors naming the key and the file. `mesh_path` is
// resolved relative to the descriptor's folder.
struct MeshDescriptor {
  std::string mesh_path;
  MeshPlacement placement;
};
absl::StatusOr<MeshDescriptor> ReadMeshDescriptor(const std::string& path);

// What a CLI flag `--mesh FILE|DESCRIPTOR.json [--mesh-scale S]
// [--mesh-pose x,y,z,qw,qx,qy,qz]` names. A .json path is a descriptor; any
// other path is a mesh file in the object frame in metres. Overrides replace
// the descriptor's values.
struct MeshRequest {
  MeshRequest() = default;
  MeshRequest(std::string mesh_path)
      : path(std::move(mesh_path)) {}  // NOLINT: implicit, LoadMesh({path})
  std::string path;
  std::optional<double> scale;
  std::optional<MeshPlacement> pose;  // position and orientation only (scale ignored)
};

struct LoadedMesh {
  TriangleMesh mesh;        // object frame, metres
  std::string name;         // file name of the mesh for messages ("Hammer.ply")
  std::string mesh_path;    // the mesh file read
  std::string format;       // "stl", "obj" or "ply"
  MeshPlacement placement;  // as applied
};
absl::StatusOr<LoadedMesh> LoadMesh(const MeshRequest& request);

// What a density fit needs of a mesh: a closed, consistently oriented
// surface (every edge traversed as often in one direction as in the other:
// shared by two triangles in opposite directions, or a junction of closed
// parts) enclosing positive volume, without degenerate faces dominating.
struct MeshCheck {
  int vertices = 0;
  int faces = 0;
  int boundary_edges = 0;  // edges used by one triangle only
  // Edges used by more than two triangles, not as many times in each
  // direction (no solid on either side is well defined).
  int non_manifold_edges = 0;
  // Edges used by 4, 6, ... triangles, as many times in each direction:
  // closed parts that touch along an edge or share a face (a hammer's head
  // and handle). The surface is still a closed oriented boundary; mass
  // properties are those of the union.
  int junction_edges = 0;
  int inconsistent_edges = 0;             // shared edges traversed twice in the same direction
  int degenerate_faces = 0;               // zero-area triangles
  double degenerate_area_fraction = 0.0;  // (tiny) area of degenerate faces / total area
  double volume = 0.0;  // signed enclosed volume (divergence theorem), mesh units^3
  double area = 0.0;
  bool closed = false;                 // boundary_edges == 0 && non_manifold_edges == 0
  bool consistently_oriented = false;  // inconsistent_edges == 0
};
MeshCheck CheckMesh(const TriangleMesh& mesh);

// OK for a closed, consistently oriented mesh of positive volume, else
// InvalidArgument naming `name` and the problem, e.g.
//   "Hammer.ply: 14 boundary edges: the mesh is not closed"
//   "box.stl: volume -0.001 m^3 is negative: the mesh is inside out (flip the winding)"
//   "part.obj: 12 edges are traversed twice in the same direction: the triangles are not
//   consistently oriented" "x.ply: 2 non-manifold edges (shared by more than two triangles)"
absl::Status RequireClosedSolid(const MeshCheck& check, std::string_view name);

struct NearestTriangle {
  int triangle = -1;
  double distance = 0.0;          // m
  Eigen::Vector3d closest;        // closest point on the mesh
  Eigen::Vector3d inward_normal;  // unit, pointing INTO the object
};

// Nearest triangle to `point` (brute force; meshes here are small).
NearestTriangle FindNearestTriangle(const TriangleMesh& mesh, const Eigen::Vector3d& point);

}  // namespace tactforce::io
