#!/usr/bin/env bash
# Builds tactforce (scripts/build.sh) and runs the whole test suite.
#   scripts/test.sh                 Release build, every test
#   scripts/test.sh --sanitize [R]  the ASan + UBSan build (build-sanitize/); every
#                                   test, or those matching the ctest regex R. Any
#                                   sanitizer report fails its test (halt_on_error).
# Env: JOBS (parallel build and test jobs, default 2).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

if [[ "${1:-}" == "--sanitize" ]]; then
  ./scripts/build.sh --sanitize
  # Leak checking stays on; suppressions only for third-party code
  # (scripts/sanitizer/lsan.supp says why each is there).
  export ASAN_OPTIONS="halt_on_error=1:detect_leaks=1:abort_on_error=1"
  export UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1"
  export LSAN_OPTIONS="suppressions=$PWD/scripts/sanitizer/lsan.supp:print_suppressions=0"
  filter=()
  [[ -n "${2:-}" ]] && filter=(-R "$2")
  exec ctest --test-dir build-sanitize --output-on-failure -j"${JOBS:-2}" "${filter[@]}"
fi
./scripts/build.sh
# Last: the closing summary line is ctest's own.
exec ctest --test-dir build --output-on-failure -j"${JOBS:-2}"
