#!/usr/bin/env bash
# Installs the Debian packages (idempotent), configures and builds tactforce.
#   scripts/build.sh              Release build in build/
#   scripts/build.sh --sanitize   ASan + UBSan build in build-sanitize/
#                                 (-fsanitize=address,undefined,float-cast-overflow:
#                                 GCC's "undefined" leaves float-to-int overflow out)
# Env: JOBS (parallel build jobs, default 2).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

dir=build
args=(-DCMAKE_BUILD_TYPE=Release)
if [[ "${1:-}" == "--sanitize" ]]; then
  dir=build-sanitize
  flags="-fsanitize=address,undefined,float-cast-overflow -fno-sanitize-recover=all -fno-omit-frame-pointer"
  # RelWithDebInfo: line numbers in reports; benchmarks are not built.
  args=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DTACTFORCE_BUILD_BENCH=OFF
        "-DCMAKE_CXX_FLAGS=$flags" "-DCMAKE_EXE_LINKER_FLAGS=$flags" "-DCMAKE_SHARED_LINKER_FLAGS=$flags")
fi
./scripts/setup.sh
cmake -S . -B "$dir" "${args[@]}"
cmake --build "$dir" -j"${JOBS:-2}"
