// Helpers shared by the mesh sources (not installed).
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <vector>

namespace tactforce::io::internal {

// One colour (0xRRGGBB) per triangle of a PLY file's faces (a polygon of n
// corners gives n - 2), from the face element's red/green/blue properties;
// nullopt when the file has none or its layout is not understood.
std::optional<std::vector<uint32_t>> PlyFaceColors(std::string_view bytes);

}  // namespace tactforce::io::internal
