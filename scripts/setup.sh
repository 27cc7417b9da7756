#!/usr/bin/env bash
# Installs every Debian 12 package tactforce needs to build, test and run.
# Idempotent: packages already installed are skipped; apt-get runs only when
# something is missing. Needs root (or sudo).
set -euo pipefail

PACKAGES=(
  build-essential cmake pkg-config git ca-certificates openssl
  libeigen3-dev
  coinor-libipopt-dev
  libnlopt-cxx-dev libnlopt-dev
  libgrpc++-dev libgrpc-dev protobuf-compiler-grpc libprotobuf-dev protobuf-compiler
  libabsl-dev
  libgtest-dev libgmock-dev
  libbenchmark-dev
  libcli11-dev
  libspdlog-dev libfmt-dev
  python3 python3-grpcio python3-protobuf python3-venv python3-pip python3-setuptools python3-wheel
  grpc-proto
  libmujoco-dev
  libassimp-dev libqhull-dev nlohmann-json3-dev
  clang libclang-rt-14-dev   # scripts/fuzz.sh: libFuzzer (libclang_rt.fuzzer), ASan, UBSan
  clang-format              # scripts/check_structure.py (ctest structure_check): every .h/.cc formatted
)

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if ((${#missing[@]} == 0)); then
  echo "setup: all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [[ $(id -u) -ne 0 ]]; then
  if command -v sudo >/dev/null; then SUDO="sudo"; else
    echo "setup: need root to install: ${missing[*]}" >&2; exit 1
  fi
fi
echo "setup: installing ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
