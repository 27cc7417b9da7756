// Helpers shared by mesh.cc and mesh_io.cc (not installed).
#pragma once

#include <string>

#include "absl/status/statusor.h"

namespace tactforce::estimator::internal {

// The whole file; InvalidArgument "path: cannot open: <reason>" otherwise.
absl::StatusOr<std::string> ReadWholeFile(const std::string& path);

}  // namespace tactforce::estimator::internal
