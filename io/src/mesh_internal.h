// Helpers shared by the mesh sources (not installed).
#pragma once

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"

namespace tactforce::io::internal {

// A PLY file checked before assimp reads it (assimp's reader crashes on
// malformed headers and allocates by the declared counts): the header line
// by line; every element's declared count against kMaxMeshVertices /
// kMaxMeshTriangles and against what the bytes after the header can hold;
// then the body item by item (ASCII: one non-blank line per item; list
// lengths within the line or the file). Errors are InvalidArgument naming
// `name` and the header line or the body line/byte.
struct CheckedPly {
  // One colour (0xRRGGBB) per triangle of the face element (a polygon of n
  // corners gives n - 2) when it has red/green/blue properties, else empty
  // (Debian's assimp 5.2 drops face colours).
  std::vector<uint32_t> face_colors;
  // When not empty, the bytes to give assimp instead of the file: the same
  // PLY with a '\n' after the header line, because assimp 5.2 skips a
  // binary body's first byte when it is '\n' after an LF-ended header and
  // misreads every value after it.
  std::string assimp_bytes;
};
absl::StatusOr<CheckedPly> CheckPly(std::string_view bytes, const std::string& name);

}  // namespace tactforce::io::internal
