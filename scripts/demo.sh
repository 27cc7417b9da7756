#!/usr/bin/env bash
# Builds tactforce and runs its demo: the built-in grasps planned with the
# geometric planner and with Ipopt, side by side. Extra arguments go to
# `tactforce demo` (e.g. --format json, --repeat 10).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

./scripts/build.sh
exec build/bin/tactforce demo "$@"
