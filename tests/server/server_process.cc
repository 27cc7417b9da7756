#include "server_process.h"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <thread>

extern char** environ;

namespace tactforce::testing {
namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

namespace {

std::string ReadAll(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

int DecodeWaitStatus(int status) {
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
  return -1;
}

// Waits for `pid` up to `timeout`; the exit code, or nullopt if still running.
std::optional<int> WaitPid(pid_t pid, std::chrono::milliseconds timeout) {
  const auto end = Clock::now() + timeout;
  for (;;) {
    int status = 0;
    const pid_t r = waitpid(pid, &status, WNOHANG);
    if (r == pid) return DecodeWaitStatus(status);
    if (r < 0 && errno != EINTR) return -1;
    if (Clock::now() >= end) return std::nullopt;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
}

std::vector<char*> CStrings(std::vector<std::string>& strings) {
  std::vector<char*> out;
  for (std::string& s : strings) out.push_back(s.data());
  out.push_back(nullptr);
  return out;
}

std::vector<std::string> Environment(const std::vector<std::string>& extra) {
  std::vector<std::string> env;
  for (char** e = environ; *e != nullptr; ++e) {
    const std::string entry(*e);
    bool overridden = false;
    for (const std::string& x : extra) {
      const auto eq = x.find('=');
      if (entry.compare(0, eq + 1, x, 0, eq + 1) == 0) overridden = true;
    }
    if (!overridden) env.push_back(entry);
  }
  env.insert(env.end(), extra.begin(), extra.end());
  return env;
}

}  // namespace

fs::path BinaryPath(const std::string& name) {
  const char* dir = std::getenv("TACTFORCE_BIN_DIR");
  return fs::path(dir != nullptr && *dir != '\0' ? dir : TACTFORCE_DEFAULT_BIN_DIR) / name;
}

fs::path SourceDir() {
  const char* dir = std::getenv("TACTFORCE_SOURCE_DIR");
  return dir != nullptr && *dir != '\0' ? dir : TACTFORCE_DEFAULT_SOURCE_DIR;
}

ProcessResult RunProcess(const std::vector<std::string>& argv_in,
                         const std::vector<std::string>& env_extra,
                         std::chrono::milliseconds timeout, const std::string& stdin_path) {
  ProcessResult run;
  const TempDir temp("tactforce_run");
  const fs::path dir = temp.path();
  const fs::path out = dir / "stdout", err = dir / "stderr";
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, stdin_path.c_str(), O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
  std::vector<std::string> args = argv_in;
  std::vector<std::string> env = Environment(env_extra);
  std::vector<char*> c_args = CStrings(args), c_env = CStrings(env);
  pid_t pid = -1;
  const int rc = posix_spawn(&pid, c_args[0], &actions, nullptr, c_args.data(), c_env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    run.err = std::string("posix_spawn failed: ") + std::strerror(rc);
    return run;
  }
  std::optional<int> code = WaitPid(pid, timeout);
  if (!code) {
    kill(pid, SIGKILL);
    code = WaitPid(pid, std::chrono::seconds(10));
    run.err = "timed out; ";
  }
  run.exit_code = code.value_or(-1);
  run.out = ReadAll(out);
  run.err += ReadAll(err);
  return run;
}

std::unique_ptr<ServerProcess> ServerProcess::Start(const std::vector<std::string>& flags,
                                                    std::string* error) {
  std::unique_ptr<ServerProcess> server(new ServerProcess());
  server->temp_ = std::make_unique<TempDir>("tactforce_server");
  server->dir_ = server->temp_->path();
  const fs::path binary = BinaryPath("tactforce-server");
  if (!fs::exists(binary)) {
    *error = "no server binary at " + binary.string();
    return nullptr;
  }
  int pipe_fds[2];
  if (pipe2(pipe_fds, O_CLOEXEC) != 0) {
    *error = "pipe2 failed";
    return nullptr;
  }
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_adddup2(&actions, pipe_fds[1], 1);
  const std::string err_path = (server->dir_ / "stderr").string();
  posix_spawn_file_actions_addopen(&actions, 2, err_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                   0600);
  std::vector<std::string> args = {binary.string(), "--listen", "127.0.0.1:0"};
  args.insert(args.end(), flags.begin(), flags.end());
  std::vector<char*> c_args = CStrings(args);
  const int rc = posix_spawn(&server->pid_, c_args[0], &actions, nullptr, c_args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  close(pipe_fds[1]);
  server->stdout_fd_ = pipe_fds[0];
  if (rc != 0) {
    server->pid_ = -1;
    *error = std::string("posix_spawn failed: ") + std::strerror(rc);
    return nullptr;
  }

  // Read the one stdout line, up to 15 s (a loaded 2-core CI box).
  const std::string prefix = "tactforce-server listening on ";
  std::string line;
  const auto end = Clock::now() + std::chrono::seconds(15);
  while (line.find('\n') == std::string::npos) {
    const int left = static_cast<int>(
        std::chrono::duration_cast<std::chrono::milliseconds>(end - Clock::now()).count());
    pollfd p{server->stdout_fd_, POLLIN, 0};
    if (left <= 0 || poll(&p, 1, left) <= 0) {
      *error = "no 'listening on' line within 15 s; stderr: " + server->StderrText();
      return nullptr;
    }
    char buffer[256];
    const ssize_t n = read(server->stdout_fd_, buffer, sizeof buffer);
    if (n <= 0) {
      server->WaitExit(std::chrono::seconds(5));
      *error = "server exited before listening (code " +
               std::to_string(server->exit_code_.value_or(-1)) +
               "); stderr: " + server->StderrText();
      return nullptr;
    }
    line.append(buffer, static_cast<size_t>(n));
  }
  line.resize(line.find('\n'));
  if (line.rfind(prefix, 0) != 0) {
    *error = "unexpected first stdout line: " + line;
    return nullptr;
  }
  server->address_ = line.substr(prefix.size());
  return server;
}

ServerProcess::~ServerProcess() {
  if (pid_ > 0 && !exit_code_) {
    kill(pid_, SIGKILL);
    WaitExit(std::chrono::seconds(10));
  }
  if (stdout_fd_ >= 0) close(stdout_fd_);
}

void ServerProcess::Signal(int signal_number) const {
  if (pid_ > 0 && !exit_code_) kill(pid_, signal_number);
}

std::optional<int> ServerProcess::WaitExit(std::chrono::milliseconds timeout) {
  if (exit_code_) return exit_code_;
  if (pid_ <= 0) return std::nullopt;
  exit_code_ = WaitPid(pid_, timeout);
  return exit_code_;
}

int ServerProcess::Stop(std::chrono::milliseconds timeout) {
  Signal(SIGTERM);
  if (std::optional<int> code = WaitExit(timeout)) return *code;
  Signal(SIGKILL);
  return WaitExit(std::chrono::seconds(10)).value_or(-1);
}

std::string ServerProcess::StderrText() const { return ReadAll(dir_ / "stderr"); }

bool ServerProcess::WaitForStderr(const std::string& needle,
                                  std::chrono::milliseconds timeout) const {
  const auto end = Clock::now() + timeout;
  for (;;) {
    if (StderrText().find(needle) != std::string::npos) return true;
    if (Clock::now() >= end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}

}  // namespace tactforce::testing
