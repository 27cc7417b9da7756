// Runs the built `tactforce` binary ($TACTFORCE_BIN_DIR/tactforce) in a
// private temporary directory and captures its exit code and output.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace tactforce::testing {

struct CliRun {
  int exit_code = -1;
  std::string out;
  std::string err;
};

// $name when set and not empty, else `fallback`.
std::string EnvOr(const char* name, const char* fallback);
// The repository root ($TACTFORCE_SOURCE_DIR, else the configured one).
std::string SourceDir();
std::string ReadFile(const std::filesystem::path& path);
void WriteFile(const std::filesystem::path& path, const std::string& text);
std::vector<std::string> Lines(const std::string& text);

class CliTest : public ::testing::Test {
 protected:
  void SetUp() override;
  void TearDown() override;

  // Writes `text` to dir()/name and returns the path.
  std::filesystem::path Write(const std::string& name, const std::string& text);
  // Runs tactforce with `args`; `stdin_text` is its standard input.
  CliRun Tactforce(const std::vector<std::string>& args, const std::string& stdin_text = "");
  // A bad-input run: exit 2, nothing on stdout, one "error: " line on stderr.
  static void ExpectBadInput(const CliRun& run);

  const std::filesystem::path& dir() const { return dir_; }

  std::filesystem::path binary_;
  std::filesystem::path dir_;
};

}  // namespace tactforce::testing
