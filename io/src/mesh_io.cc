// Mesh files through assimp: STL, OBJ and PLY to an indexed TriangleMesh with
// vertices welded by exact position.
#include <algorithm>
#include <array>
#include <cmath>
#include <exception>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "absl/container/flat_hash_map.h"
#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/text_file.h"
#include "mesh_internal.h"

namespace tactforce::io {
namespace {

// Exact-position key; -0.0 and 0.0 are the same point.
using PositionKey = std::array<double, 3>;

uint32_t PackColor(const aiColor4D& c) {
  auto channel = [](float v) {
    const float clamped = std::clamp(v, 0.0f, 1.0f);
    return static_cast<uint32_t>(std::lround(clamped * 255.0f));
  };
  return channel(c.r) << 16 | channel(c.g) << 8 | channel(c.b);
}

// Average colour of a triangle's corners (per-vertex colours; per-face colours
// that assimp maps to vertices, e.g. binary STL, come out exact).
uint32_t FaceColor(const aiMesh& m, const aiFace& f) {
  aiColor4D sum(0, 0, 0, 0);
  for (unsigned k = 0; k < 3; ++k) sum = sum + m.mColors[0][f.mIndices[k]];
  return PackColor(sum / 3.0f);
}

absl::StatusOr<TriangleMesh> FromScene(const aiScene& scene, const std::string& name) {
  size_t corners = 0;
  bool colored = scene.mNumMeshes > 0;
  for (unsigned i = 0; i < scene.mNumMeshes; ++i) {
    corners += scene.mMeshes[i]->mNumVertices;
    colored = colored && scene.mMeshes[i]->HasVertexColors(0);
  }
  TriangleMesh mesh;
  absl::flat_hash_map<PositionKey, int> index_of;
  index_of.reserve(corners);
  mesh.vertices.reserve(corners);
  std::vector<int> welded;
  for (unsigned i = 0; i < scene.mNumMeshes; ++i) {
    const aiMesh& m = *scene.mMeshes[i];
    welded.assign(m.mNumVertices, -1);
    for (unsigned v = 0; v < m.mNumVertices; ++v) {
      const aiVector3D& p = m.mVertices[v];
      const PositionKey key = {double(p.x) + 0.0, double(p.y) + 0.0, double(p.z) + 0.0};
      if (!std::isfinite(key[0]) || !std::isfinite(key[1]) || !std::isfinite(key[2]))
        return absl::InvalidArgumentError(absl::StrCat(name, ": vertex ", v, " is not finite"));
      const auto [it, added] = index_of.try_emplace(key, static_cast<int>(mesh.vertices.size()));
      if (added) mesh.vertices.emplace_back(key[0], key[1], key[2]);
      welded[v] = it->second;
    }
    for (unsigned t = 0; t < m.mNumFaces; ++t) {
      const aiFace& f = m.mFaces[t];
      if (f.mNumIndices != 3) continue;  // points and lines: not surface
      mesh.triangles.push_back({welded[f.mIndices[0]], welded[f.mIndices[1]], welded[f.mIndices[2]]});
      if (colored) mesh.face_colors.push_back(FaceColor(m, f));
    }
  }
  if (mesh.triangles.empty()) return absl::InvalidArgumentError(absl::StrCat(name, ": no triangles"));
  return mesh;
}

}  // namespace

absl::StatusOr<std::string> MeshFormatFromPath(const std::string& path) {
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  if (ext == ".stl" || ext == ".obj" || ext == ".ply") return ext.substr(1);
  return absl::InvalidArgumentError(absl::StrCat(path, ": unknown mesh format '", ext,
                                                 "' (expected .stl, .obj or .ply)"));
}

absl::StatusOr<TriangleMesh> ReadMeshBytes(std::string_view bytes, std::string_view format,
                                           std::string_view name_view) {
  const std::string name(name_view);
  const std::string hint = absl::AsciiStrToLower(std::string(format));
  if (hint != "stl" && hint != "obj" && hint != "ply")
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": unknown mesh format '", std::string(format), "' (expected stl, obj or ply)"));
  if (bytes.empty()) return absl::InvalidArgumentError(absl::StrCat(name, ": empty file"));
  // No DefaultLogger is created, so assimp logs to its silent NullLogger.
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  try {
    // Validation runs first: assimp's readers do not check face indices (a
    // truncated binary PLY has faces pointing past the vertices), and
    // triangulating or welding such faces reads out of bounds.
    scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(),
                                        aiProcess_ValidateDataStructure | aiProcess_Triangulate, hint.c_str());
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": assimp: ", e.what()));
  }
  if (scene == nullptr) {
    std::string message = importer.GetErrorString();
    if (message.empty()) message = "cannot read the file";
    return absl::InvalidArgumentError(absl::StrCat(name, ": assimp: ", message));
  }
  absl::StatusOr<TriangleMesh> mesh = FromScene(*scene, name);
  if (mesh.ok() && hint == "ply" && mesh->face_colors.empty()) {
    // assimp keeps the file's face order; a count mismatch means it did not.
    std::optional<std::vector<uint32_t>> colors = internal::PlyFaceColors(bytes);
    if (colors && colors->size() == mesh->triangles.size()) mesh->face_colors = *std::move(colors);
  }
  return mesh;
}

absl::StatusOr<TriangleMesh> ReadMeshFile(const std::string& path) {
  absl::StatusOr<std::string> format = MeshFormatFromPath(path);
  if (!format.ok()) return format.status();
  absl::StatusOr<std::string> bytes = ReadTextFile(path);
  if (!bytes.ok()) return bytes.status();
  return ReadMeshBytes(*bytes, *format, path);
}

}  // namespace tactforce::io
