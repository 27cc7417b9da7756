// Mesh reading from memory (io::ReadMeshBytes: assimp + our welding, PLY face
// colours), then our checks on what it returns (ValidateMesh, CheckMesh,
// FindNearestTriangle). The first byte picks the format (byte % 3):
// 0 ('0') STL, 1 ('1') OBJ, 2 ('2') PLY.
#include <cstddef>
#include <cstdint>

#include "absl/strings/str_cat.h"
#include "fuzz_util.h"
#include "tactforce/io/mesh.h"

namespace {

constexpr const char* kFormats[] = {"stl", "obj", "ply"};

void CheckReadMesh(const tactforce::io::TriangleMesh& mesh) {
  const int n = static_cast<int>(mesh.vertices.size());
  for (const auto& t : mesh.triangles) {
    for (int i : t) {
      if (i < 0 || i >= n)
        tactforce::fuzz::Fail("mesh", absl::StrCat("index ", i, " of ", n, " vertices"));
    }
  }
  if (!mesh.face_colors.empty() && mesh.face_colors.size() != mesh.triangles.size()) {
    tactforce::fuzz::Fail("mesh", absl::StrCat(mesh.face_colors.size(), " colours for ",
                                               mesh.triangles.size(), " triangles"));
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1 || size > tactforce::fuzz::kMaxInputBytes) return 0;
  const char* format = kFormats[data[0] % 3];
  absl::StatusOr<tactforce::io::TriangleMesh> mesh =
      tactforce::io::ReadMeshBytes(tactforce::fuzz::Bytes(data + 1, size - 1), format, "fuzz");
  if (!mesh.ok()) return 0;
  CheckReadMesh(*mesh);
  (void)tactforce::io::ValidateMesh(*mesh);
  const tactforce::io::MeshCheck check = tactforce::io::CheckMesh(*mesh);
  (void)tactforce::io::RequireClosedSolid(check, "fuzz");
  (void)tactforce::io::FindNearestTriangle(*mesh, Eigen::Vector3d::Zero());
  return 0;
}
