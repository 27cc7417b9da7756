#include "support/temp_dir.h"

#include <stdlib.h>

#include <fstream>

namespace tactforce::testing {

TempDir::TempDir(const std::string& stem) {
  std::string pattern = (std::filesystem::temp_directory_path() / (stem + ".XXXXXX")).string();
  if (mkdtemp(pattern.data()) != nullptr) dir_ = pattern;
}

TempDir::~TempDir() {
  std::error_code ignored;
  if (!dir_.empty()) std::filesystem::remove_all(dir_, ignored);
}

std::string TempDir::Write(const std::string& name, const std::string& text) const {
  const std::filesystem::path path = dir_ / name;
  std::ofstream(path, std::ios::binary) << text;
  return path.string();
}

}  // namespace tactforce::testing
