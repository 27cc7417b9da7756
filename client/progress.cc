// The stderr progress bar: redrawn in place on a terminal (at most every
// 100 ms), one line per 10 % step otherwise.
#include "progress.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <iostream>

#include "absl/strings/str_format.h"

namespace tactforce::cli {

ProgressBar::ProgressBar(std::string label, bool enabled, std::chrono::milliseconds quiet_for)
    : label_(std::move(label)),
      enabled_(enabled),
      tty_(StderrIsTerminal()),
      quiet_for_(quiet_for) {}

bool ProgressBar::StderrIsTerminal() { return isatty(fileno(stderr)) == 1; }

void ProgressBar::Update(double fraction, const std::string& detail) {
  if (!enabled_) return;
  const auto now = std::chrono::steady_clock::now();
  if (now - start_ < quiet_for_) return;
  fraction = std::clamp(fraction, 0.0, 1.0);
  const int decile = static_cast<int>(fraction * 10.0);
  if (tty_) {
    if (shown_ && now - last_ < std::chrono::milliseconds(100) && fraction < 1.0) return;
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth + 0.5);
    std::cerr << "\r" << label_ << " [" << std::string(filled, '#')
              << std::string(kWidth - filled, '.') << "] "
              << absl::StrFormat("%3.0f%%", 100.0 * fraction) << (detail.empty() ? "" : " ")
              << detail << "\x1b[K" << std::flush;
  } else {
    if (decile <= last_decile_) return;
    std::cerr << label_ << ": " << absl::StrFormat("%.0f%%", 100.0 * fraction)
              << (detail.empty() ? "" : " ") << detail << std::endl;
  }
  last_decile_ = std::max(last_decile_, decile);
  last_ = now;
  shown_ = true;
}

void ProgressBar::Finish() {
  if (tty_ && shown_) std::cerr << "\r\x1b[K" << std::flush;
  shown_ = false;
}

}  // namespace tactforce::cli
