// Mesh files through assimp: STL, OBJ and PLY to an indexed TriangleMesh with
// vertices welded by exact position.
#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <cmath>
#include <exception>
#include <new>
#include <filesystem>
#include <numeric>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <assimp/IOSystem.hpp>
#include <assimp/MemoryIOWrapper.h>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include "absl/strings/ascii.h"
#include "absl/strings/str_cat.h"
#include "tactforce/io/mesh.h"
#include "tactforce/io/text_file.h"
#include "mesh_internal.h"
#include "tactforce/io/status_macros.h"

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
uint32_t FaceColor(const aiMesh& m, unsigned a, unsigned b, unsigned c) {
  return PackColor((m.mColors[0][a] + m.mColors[0][b] + m.mColors[0][c]) / 3.0f);
}

// The vertex of every corner of the scene's meshes (meshes one after
// another), vertices welded by exact position and numbered in order of first
// appearance. By sorting, not with a hash map: absl's flat_hash_map is left
// corrupt when an allocation throws (its destructor frees an invalid
// pointer), and a read must survive running out of memory.
absl::StatusOr<std::vector<int>> Weld(const aiScene& scene, const std::string& name,
                                      std::vector<Eigen::Vector3d>* vertices) {
  std::vector<PositionKey> keys;
  for (unsigned i = 0; i < scene.mNumMeshes; ++i) {
    const aiMesh& m = *scene.mMeshes[i];
    for (unsigned v = 0; v < m.mNumVertices; ++v) {
      const aiVector3D& p = m.mVertices[v];
      const PositionKey key = {double(p.x) + 0.0, double(p.y) + 0.0, double(p.z) + 0.0};
      if (!std::isfinite(key[0]) || !std::isfinite(key[1]) || !std::isfinite(key[2]))
        return absl::InvalidArgumentError(absl::StrCat(name, ": vertex ", v, " is not finite"));
      keys.push_back(key);
    }
  }
  std::vector<size_t> order(keys.size());
  std::iota(order.begin(), order.end(), size_t{0});
  std::sort(order.begin(), order.end(),
            [&](size_t a, size_t b) { return keys[a] != keys[b] ? keys[a] < keys[b] : a < b; });
  std::vector<size_t> first(keys.size());  // the first corner at the same position
  for (size_t i = 0; i < order.size(); ++i)
    first[order[i]] =
        i > 0 && keys[order[i]] == keys[order[i - 1]] ? first[order[i - 1]] : order[i];
  std::vector<int> vertex_of(keys.size(), -1);
  for (size_t c = 0; c < keys.size(); ++c) {
    if (vertex_of[first[c]] < 0) {  // first[c] <= c: set here when c is the first
      vertex_of[first[c]] = static_cast<int>(vertices->size());
      vertices->emplace_back(keys[c][0], keys[c][1], keys[c][2]);
    }
    vertex_of[c] = vertex_of[first[c]];
  }
  return vertex_of;
}

absl::StatusOr<TriangleMesh> FromScene(const aiScene& scene, const std::string& name) {
  bool colored = scene.mNumMeshes > 0;
  for (unsigned i = 0; i < scene.mNumMeshes; ++i)
    colored = colored && scene.mMeshes[i]->HasVertexColors(0);
  TriangleMesh mesh;
  TF_ASSIGN_OR_RETURN(const std::vector<int> vertex_of, Weld(scene, name, &mesh.vertices));
  size_t first_corner = 0;  // of the current mesh in vertex_of
  for (unsigned i = 0; i < scene.mNumMeshes; ++i) {
    const aiMesh& m = *scene.mMeshes[i];
    const int* welded = vertex_of.data() + first_corner;
    first_corner += m.mNumVertices;
    // Polygons as fans (assimp's own triangulation aborts on some malformed
    // PLY faces); points and lines are not surface.
    for (unsigned t = 0; t < m.mNumFaces; ++t) {
      const aiFace& f = m.mFaces[t];
      for (unsigned k = 0; k < f.mNumIndices; ++k) {
        if (f.mIndices[k] >= m.mNumVertices)
          return absl::InvalidArgumentError(
              absl::StrCat(name, ": face ", t, " refers to a missing vertex"));
      }
      for (unsigned k = 1; k + 1 < f.mNumIndices; ++k) {
        const unsigned a = f.mIndices[0], b = f.mIndices[k], c = f.mIndices[k + 1];
        mesh.triangles.push_back({welded[a], welded[b], welded[c]});
        if (colored) mesh.face_colors.push_back(FaceColor(m, a, b, c));
      }
    }
  }
  if (mesh.triangles.empty())
    return absl::InvalidArgumentError(absl::StrCat(name, ": no triangles"));
  return mesh;
}

}  // namespace

absl::StatusOr<std::string> MeshFormatFromPath(const std::string& path) {
  const std::string ext = absl::AsciiStrToLower(std::filesystem::path(path).extension().string());
  if (ext == ".stl" || ext == ".obj" || ext == ".ply") return ext.substr(1);
  return absl::InvalidArgumentError(
      absl::StrCat(path, ": unknown mesh format '", ext, "' (expected .stl, .obj or .ply)"));
}

namespace {

// The only file assimp may open: the request's bytes, under a name no file
// statement can spell. Every other name (an OBJ's `mtllib /etc/passwd`, a
// FIFO that blocks the reader forever, the OBJ reader's fallback of its own
// name with ".mtl") is refused, so request bytes never reach the file system.
// assimp's ReadFileFromMemory is not used: its reader serves every name that
// starts with its magic prefix, so that fallback parsed the OBJ again as MTL
// (a texture line before `newmtl` then wrote through a null material).
class OneBufferIOSystem : public Assimp::IOSystem {
 public:
  // An OBJ statement ends at a line end, so no `mtllib` can name this file.
  static std::string NameFor(const std::string& hint) { return "request\n." + hint; }

  OneBufferIOSystem(std::string name, std::string_view bytes)
      : name_(std::move(name)), bytes_(bytes) {}
  bool Exists(const char* file) const override { return file != nullptr && name_ == file; }
  char getOsSeparator() const override { return '/'; }
  Assimp::IOStream* Open(const char* file, const char* mode) override {
    if (!Exists(file) || mode == nullptr || mode[0] != 'r') return nullptr;
    return new Assimp::MemoryIOStream(reinterpret_cast<const uint8_t*>(bytes_.data()),
                                      bytes_.size());
  }
  void Close(Assimp::IOStream* stream) override { delete stream; }

 private:
  std::string name_;
  std::string_view bytes_;
};

// A binary STL's triangle count against the file size, before assimp reads
// it: assimp computes 84 + 50 n in 32 bits, so a count such as 2^31 + 1
// passes its own size check and it allocates n faces.
absl::Status CheckStl(std::string_view bytes, const std::string& name) {
  if (bytes.size() < 84) return absl::OkStatus();  // too short for binary; assimp tries ASCII
  uint32_t triangles = 0;
  std::memcpy(&triangles, bytes.data() + 80, sizeof(triangles));  // little-endian, as the format
  const uint64_t needed = 84 + 50 * uint64_t{triangles};
  if (needed == bytes.size()) return absl::OkStatus();
  const absl::string_view start = absl::StripLeadingAsciiWhitespace(
      absl::string_view(bytes.data(), std::min<size_t>(bytes.size(), 512)));
  const bool wraps = static_cast<uint32_t>(needed) == bytes.size();
  if (!wraps && start.substr(0, 5) == "solid") return absl::OkStatus();  // ASCII STL
  return absl::InvalidArgumentError(
      absl::StrCat(name, ": binary STL header declares ", triangles, " triangles (", needed,
                   " bytes) but the file has ", bytes.size(), " bytes"));
}

absl::Status CheckLimits(const TriangleMesh& mesh, const std::string& name) {
  if (mesh.vertices.size() > static_cast<size_t>(kMaxMeshVertices))
    return absl::InvalidArgumentError(absl::StrCat(
        name, ": ", mesh.vertices.size(), " vertices, more than the limit of ", kMaxMeshVertices));
  if (mesh.triangles.size() > static_cast<size_t>(kMaxMeshTriangles))
    return absl::InvalidArgumentError(absl::StrCat(name, ": ", mesh.triangles.size(),
                                                   " triangles, more than the limit of ",
                                                   kMaxMeshTriangles));
  return absl::OkStatus();
}

// ReadMeshBytes without its exception guard; `hint` is "stl", "obj" or "ply".
absl::StatusOr<TriangleMesh> ReadMesh(std::string_view bytes, const std::string& hint,
                                      const std::string& name) {
  internal::CheckedPly ply;
  if (hint == "ply") {
    TF_ASSIGN_OR_RETURN(ply, internal::CheckPly(bytes, name));
    if (!ply.assimp_bytes.empty()) bytes = ply.assimp_bytes;
  }
  if (hint == "stl") {
    TF_RETURN_IF_ERROR(CheckStl(bytes, name));
  }
  // No DefaultLogger is created, so assimp logs to its silent NullLogger.
  Assimp::Importer importer;
  const std::string file = OneBufferIOSystem::NameFor(hint);
  importer.SetIOHandler(new OneBufferIOSystem(file, bytes));  // owned by the importer
  // Validation: assimp's readers do not check face indices (a truncated
  // binary PLY has faces pointing past the vertices); FromScene checks again.
  const aiScene* scene = importer.ReadFile(file, aiProcess_ValidateDataStructure);
  // assimp catches what its readers throw and keeps it: std::bad_alloc
  // becomes ResourceExhausted in ReadMeshBytes rather than a parse error.
  if (scene == nullptr && importer.GetException()) std::rethrow_exception(importer.GetException());
  if (scene == nullptr) {
    std::string message = importer.GetErrorString();
    if (message.empty()) message = "cannot read the file";
    return absl::InvalidArgumentError(absl::StrCat(name, ": assimp: ", message));
  }
  TF_ASSIGN_OR_RETURN(TriangleMesh mesh, FromScene(*scene, name));
  TF_RETURN_IF_ERROR(CheckLimits(mesh, name));
  // assimp keeps the file's face order; a count mismatch means it did not.
  if (mesh.face_colors.empty() && ply.face_colors.size() == mesh.triangles.size())
    mesh.face_colors = std::move(ply.face_colors);
  return mesh;
}

}  // namespace

absl::StatusOr<TriangleMesh> ReadMeshBytes(std::string_view bytes, std::string_view format,
                                           std::string_view name_view) {
  const std::string name(name_view);
  const std::string hint = absl::AsciiStrToLower(std::string(format));
  if (hint != "stl" && hint != "obj" && hint != "ply")
    return absl::InvalidArgumentError(absl::StrCat(
        name, ": unknown mesh format '", std::string(format), "' (expected stl, obj or ply)"));
  if (bytes.empty()) return absl::InvalidArgumentError(absl::StrCat(name, ": empty file"));
  // No exception leaves: assimp's, our containers' and the PLY check's become a Status.
  try {
    return ReadMesh(bytes, hint, name);
  } catch (const std::bad_alloc&) {
    return absl::ResourceExhaustedError(
        absl::StrCat(name, ": out of memory while reading the mesh"));
  } catch (const std::exception& e) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": cannot read the mesh: ", e.what()));
  } catch (...) {
    return absl::InvalidArgumentError(absl::StrCat(name, ": cannot read the mesh"));
  }
}

absl::StatusOr<TriangleMesh> ReadMeshFile(const std::string& path) {
  TF_ASSIGN_OR_RETURN(std::string format, MeshFormatFromPath(path));
  TF_ASSIGN_OR_RETURN(std::string bytes, ReadTextFile(path));
  return ReadMeshBytes(bytes, format, path);
}

}  // namespace tactforce::io
