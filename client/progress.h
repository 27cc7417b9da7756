// A one-line progress bar on stderr for long CLI work (inertia fits,
// uploads, experiment batches): rewritten in place on a terminal, one line
// per 10 % step otherwise (so logs stay short). Thread-compatible, not
// thread-safe: call from one thread.
#pragma once

#include <chrono>
#include <string>

namespace tactforce::cli {

class ProgressBar {
 public:
  // `label`: what is progressing ("fit", "upload"). `enabled` false: silent.
  // Nothing is printed during the first `quiet_for` (short work stays quiet).
  ProgressBar(std::string label, bool enabled,
              std::chrono::milliseconds quiet_for = std::chrono::milliseconds(300));
  ~ProgressBar() { Finish(); }
  ProgressBar(const ProgressBar&) = delete;
  ProgressBar& operator=(const ProgressBar&) = delete;

  // fraction in [0, 1] (clamped); `detail` is appended ("1200/5000 samples").
  void Update(double fraction, const std::string& detail = {});
  // Clears the line on a terminal; idempotent.
  void Finish();

  // True when stderr is a terminal (the default for --progress flags).
  static bool StderrIsTerminal();

 private:
  std::string label_;
  bool enabled_;
  bool tty_;
  std::chrono::milliseconds quiet_for_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  std::chrono::steady_clock::time_point last_ = start_;
  int last_decile_ = -1;
  bool shown_ = false;
};

}  // namespace tactforce::cli
