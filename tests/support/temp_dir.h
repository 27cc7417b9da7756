// The tests' one temporary-directory helper: a private directory
// (mkdtemp under the system temp dir), removed with everything in it when
// the object goes.
#pragma once

#include <filesystem>
#include <string>

namespace tactforce::testing {

class TempDir {
 public:
  // `stem` names the directory (stem.XXXXXX), for finding leftovers.
  explicit TempDir(const std::string& stem = "tactforce_test");
  ~TempDir();
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;

  // Writes `text` to dir/name (binary) and returns the path.
  std::string Write(const std::string& name, const std::string& text) const;
  // dir/name, as text.
  std::string Path(const std::string& name) const { return (dir_ / name).string(); }
  // The directory; empty when it could not be made.
  const std::filesystem::path& path() const { return dir_; }

 private:
  std::filesystem::path dir_;
};

}  // namespace tactforce::testing
