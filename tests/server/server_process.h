// Runs the real tactforce-server binary for a test: spawned with
// --listen 127.0.0.1:0 (plus any flags), the bound address read from its
// "tactforce-server listening on HOST:PORT" stdout line, stderr captured to
// a file. The destructor kills and reaps it, so no process outlives a test.
#pragma once

#include <sys/types.h>

#include <chrono>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "support/temp_dir.h"

namespace tactforce::testing {

struct ProcessResult {
  int exit_code = -1;  // 128 + signal when killed by a signal
  std::string out;
  std::string err;
};

// $TACTFORCE_BIN_DIR/<name>; the build's bin/ when the variable is unset.
std::filesystem::path BinaryPath(const std::string& name);
// $TACTFORCE_SOURCE_DIR, or the source tree this was built from.
std::filesystem::path SourceDir();

// Runs `argv` to completion (stdin from `stdin_path`), capturing output;
// `env` entries ("K=V") are added to the environment. Kills it after
// `timeout`.
ProcessResult RunProcess(const std::vector<std::string>& argv,
                         const std::vector<std::string>& env = {},
                         std::chrono::milliseconds timeout = std::chrono::seconds(30),
                         const std::string& stdin_path = "/dev/null");

class ServerProcess {
 public:
  // Starts tactforce-server with `--listen 127.0.0.1:0` and `flags`; on
  // failure returns null and fills `error` (with the server's stderr).
  static std::unique_ptr<ServerProcess> Start(const std::vector<std::string>& flags,
                                              std::string* error);
  ~ServerProcess();

  const std::string& address() const { return address_; }
  pid_t pid() const { return pid_; }

  void Signal(int signal_number) const;
  // Exit code once the process has ended within `timeout`, else nullopt.
  std::optional<int> WaitExit(std::chrono::milliseconds timeout);
  // SIGTERM, then SIGKILL if it has not exited after `timeout`; exit code.
  int Stop(std::chrono::milliseconds timeout = std::chrono::seconds(15));
  // Everything the server wrote to stderr so far.
  std::string StderrText() const;
  // Polls StderrText() until it contains `needle` (true) or `timeout`.
  bool WaitForStderr(const std::string& needle, std::chrono::milliseconds timeout) const;

 private:
  ServerProcess() = default;

  pid_t pid_ = -1;
  int stdout_fd_ = -1;
  std::optional<int> exit_code_;
  std::unique_ptr<TempDir> temp_;  // removed with the process object
  std::filesystem::path dir_;
  std::string address_;
};

}  // namespace tactforce::testing
