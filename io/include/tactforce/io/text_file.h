// Whole files in and out (CSV, JSON, SVG, meshes), and where a byte offset
// sits in a text (for file:line:column messages). Errors are InvalidArgument
// naming the path:
//   "<path>: cannot open: <reason>", "<path>: cannot read: <reason>",
//   "<path>: cannot open for writing", "<path>: write failed".
#pragma once

#include <cstddef>
#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tactforce::io {

// The file's bytes exactly as stored (binary-safe: no newline translation,
// NUL bytes kept), text or binary (STL, PLY). "-" reads standard input (to
// its end; a second "-" then reads nothing).
absl::StatusOr<std::string> ReadTextFile(const std::string& path);
// How `path` is named in messages: "<stdin>" for "-", else the path.
std::string SourceName(const std::string& path);
// Writes to "<path>.tmp-<pid>-<n>" and renames it over `path` when complete,
// so a reader never sees a half-written file and a failed write leaves the
// old file; devices and pipes (not regular files) are written directly.
absl::Status WriteTextFile(const std::string& path, std::string_view text);

// 1-based line and column (in bytes) of the byte at `offset` in `text`; an
// offset at or past the end names the position just after the last byte.
struct TextPosition {
  int line = 1;
  int column = 1;
};
TextPosition PositionInText(std::string_view text, size_t offset);

}  // namespace tactforce::io
