// CliTest: runs the built `tactforce` through the shell with its standard
// streams redirected to files in a private temporary directory, and the
// small file helpers the CLI suites share.
#include "support/cli_fixture.h"

#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace tactforce::testing {
namespace fs = std::filesystem;
namespace {

std::string Quote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

}  // namespace

std::string EnvOr(const char* name, const char* fallback) {
  const char* value = std::getenv(name);
  return value != nullptr && *value != '\0' ? value : fallback;
}

std::string SourceDir() { return EnvOr("TACTFORCE_SOURCE_DIR", TACTFORCE_DEFAULT_SOURCE_DIR); }

std::string ReadFile(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

void WriteFile(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

std::vector<std::string> Lines(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

void CliTest::SetUp() {
  binary_ = fs::path(EnvOr("TACTFORCE_BIN_DIR", TACTFORCE_DEFAULT_BIN_DIR)) / "tactforce";
  ASSERT_TRUE(fs::exists(binary_)) << binary_;
  std::string pattern = (fs::temp_directory_path() / "tactforce_cli_test.XXXXXX").string();
  ASSERT_NE(mkdtemp(pattern.data()), nullptr);
  dir_ = pattern;
}

void CliTest::TearDown() {
  std::error_code ec;
  if (!dir_.empty()) fs::remove_all(dir_, ec);
}

fs::path CliTest::Write(const std::string& name, const std::string& text) {
  WriteFile(dir_ / name, text);
  return dir_ / name;
}

CliRun CliTest::Tactforce(const std::vector<std::string>& args, const std::string& stdin_text) {
  const fs::path in = Write("stdin.txt", stdin_text);
  const fs::path out = dir_ / "stdout.txt";
  const fs::path err = dir_ / "stderr.txt";
  std::string command = Quote(binary_.string());
  for (const std::string& a : args) command += " " + Quote(a);
  command += " <" + Quote(in.string()) + " >" + Quote(out.string()) + " 2>" + Quote(err.string());
  const int status = std::system(command.c_str());
  CliRun run;
  if (status != -1 && WIFEXITED(status)) run.exit_code = WEXITSTATUS(status);
  run.out = ReadFile(out);
  run.err = ReadFile(err);
  return run;
}

void CliTest::ExpectBadInput(const CliRun& run) {
  EXPECT_EQ(run.exit_code, 2) << run.err;
  EXPECT_EQ(run.out, "");
  ASSERT_EQ(Lines(run.err).size(), 1u) << run.err;
  EXPECT_EQ(run.err.rfind("error: ", 0), 0u) << run.err;
}

}  // namespace tactforce::testing
