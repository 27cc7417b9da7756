// Shared by the libFuzzer targets of tests/fuzz (see README.md there).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <string_view>

namespace tactforce::fuzz {

// Inputs larger than this are skipped: the per-input cost stays small and
// the interesting bugs are in the structure of an input, not its length.
inline constexpr size_t kMaxInputBytes = 64 * 1024;

inline std::string_view Bytes(const uint8_t* data, size_t size) {
  return {reinterpret_cast<const char*>(data), size};
}

// A broken invariant of OUR code: print it and abort, so that libFuzzer
// (and the replay ctest) report a crash with this input.
[[noreturn]] inline void Fail(const char* what, const std::string& detail) {
  std::fprintf(stderr, "fuzz invariant broken: %s: %s\n", what, detail.c_str());
  std::abort();
}

inline bool AllFinite(std::initializer_list<double> values) {
  for (double v : values) {
    if (!std::isfinite(v)) return false;
  }
  return true;
}

}  // namespace tactforce::fuzz
