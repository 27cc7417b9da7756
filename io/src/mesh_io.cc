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
#include "absl/container/flat_hash_set.h"
#include "absl/strings/ascii.h"
#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"
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
uint32_t FaceColor(const aiMesh& m, unsigned a, unsigned b, unsigned c) {
  return PackColor((m.mColors[0][a] + m.mColors[0][b] + m.mColors[0][c]) / 3.0f);
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
    // Polygons as fans (assimp's own triangulation aborts on some malformed
    // PLY faces: found by the mesh fuzzer); points and lines are not surface.
    for (unsigned t = 0; t < m.mNumFaces; ++t) {
      const aiFace& f = m.mFaces[t];
      for (unsigned k = 0; k < f.mNumIndices; ++k) {
        if (f.mIndices[k] >= m.mNumVertices)
          return absl::InvalidArgumentError(absl::StrCat(name, ": face ", t, " refers to a missing vertex"));
      }
      for (unsigned k = 1; k + 1 < f.mNumIndices; ++k) {
        const unsigned a = f.mIndices[0], b = f.mIndices[k], c = f.mIndices[k + 1];
        mesh.triangles.push_back({welded[a], welded[b], welded[c]});
        if (colored) mesh.face_colors.push_back(FaceColor(m, a, b, c));
      }
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

namespace {

// The PLY header, checked line by line before assimp sees the bytes: its
// PLY reader reads past the end of a header that stops early or hides
// `end_header` inside another line (SEGV), and asserts (abort) on unknown
// property types; all found by the mesh fuzzer. Accepted lines: "ply",
// one "format ascii|binary_little_endian|binary_big_endian 1.0", "comment
// ...", "obj_info ...", "element NAME COUNT", "property TYPE NAME",
// "property list TYPE TYPE NAME", then "end_header".
absl::Status CheckPlyHeader(std::string_view std_bytes, const std::string& name) {
  const absl::string_view bytes(std_bytes.data(), std_bytes.size());
  static const absl::flat_hash_set<absl::string_view> kTypes = {
      "char", "uchar", "short", "ushort", "int", "uint", "float", "double", "int8", "uint8",
      "int16", "uint16", "int32", "uint32", "float32", "float64"};
  int line_number = 0;
  bool format = false, element = false;
  size_t pos = 0;
  while (pos < bytes.size()) {
    const size_t eol = bytes.find('\n', pos);
    absl::string_view line = bytes.substr(pos, eol == absl::string_view::npos ? absl::string_view::npos : eol - pos);
    pos = eol == absl::string_view::npos ? bytes.size() : eol + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    auto bad = [&](const std::string& what) {
      return absl::InvalidArgumentError(absl::StrCat(name, ": PLY header line ", line_number, ": ", what));
    };
    for (char c : line) {
      if (c != '\t' && (c < ' ' || c > '~')) return bad("binary bytes inside the header");
    }
    const std::vector<absl::string_view> w = absl::StrSplit(line, ' ', absl::SkipEmpty());
    if (line_number == 1) {
      if (line != "ply") return bad("not a PLY file (the first line must be 'ply')");
      continue;
    }
    if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
    if (w[0] == "end_header" && w.size() == 1) {
      if (!format) return bad("'end_header' before a 'format' line");
      return absl::OkStatus();
    }
    uint64_t count = 0;
    if (w[0] == "format" && !format && w.size() == 3 && w[2] == "1.0" &&
        (w[1] == "ascii" || w[1] == "binary_little_endian" || w[1] == "binary_big_endian")) {
      format = true;
    } else if (w[0] == "element" && w.size() == 3 && absl::SimpleAtoi(w[2], &count)) {
      element = true;
    } else if (w[0] == "property" && element &&
               ((w.size() == 3 && kTypes.contains(w[1])) ||
                (w.size() == 5 && w[1] == "list" && kTypes.contains(w[2]) && kTypes.contains(w[3])))) {
    } else {
      return bad(absl::StrCat("unexpected '", line.substr(0, 40), "'"));
    }
  }
  return absl::InvalidArgumentError(absl::StrCat(name, ": not a PLY file: no 'end_header' line"));
}

}  // namespace

absl::StatusOr<TriangleMesh> ReadMeshBytes(std::string_view bytes, std::string_view format,
                                           std::string_view name_view) {
  const std::string name(name_view);
  const std::string hint = absl::AsciiStrToLower(std::string(format));
  if (hint != "stl" && hint != "obj" && hint != "ply")
    return absl::InvalidArgumentError(
        absl::StrCat(name, ": unknown mesh format '", std::string(format), "' (expected stl, obj or ply)"));
  if (bytes.empty()) return absl::InvalidArgumentError(absl::StrCat(name, ": empty file"));
  if (hint == "ply") {
    if (absl::Status header = CheckPlyHeader(bytes, name); !header.ok()) return header;
  }
  // No DefaultLogger is created, so assimp logs to its silent NullLogger.
  Assimp::Importer importer;
  const aiScene* scene = nullptr;
  try {
    // Validation: assimp's readers do not check face indices (a truncated
    // binary PLY has faces pointing past the vertices); FromScene checks again.
    scene = importer.ReadFileFromMemory(bytes.data(), bytes.size(), aiProcess_ValidateDataStructure, hint.c_str());
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
