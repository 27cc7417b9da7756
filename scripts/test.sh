#!/usr/bin/env bash
# Builds tactforce (scripts/build.sh) and runs the whole test suite.
# Env: JOBS (parallel build and test jobs, default 2).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

./scripts/build.sh
# Last: the closing summary line is ctest's own.
exec ctest --test-dir build --output-on-failure -j"${JOBS:-2}"
