// Reading and writing whole text files (CSV, JSON, SVG) for the sim, audit
// and inertia libraries. Errors are InvalidArgument naming the path:
// "<path>: cannot open", "<path>: cannot open for writing", "<path>: write failed".
#pragma once

#include <string>
#include <string_view>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace tactforce::io {

absl::StatusOr<std::string> ReadTextFile(const std::string& path);
absl::Status WriteTextFile(const std::string& path, std::string_view text);

}  // namespace tactforce::io
