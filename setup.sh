#!/usr/bin/env bash
# Installs triadcal's build dependencies (Debian 12 packages) and builds it in build/.
# Usage: ./setup.sh        (uses sudo for apt-get when not run as root)
set -euo pipefail
cd "$(dirname "$0")"

packages=(build-essential cmake ninja-build pkg-config
          libceres-dev libeigen3-dev libsuitesparse-dev libcli11-dev libgtest-dev
          libyaml-cpp-dev nlohmann-json3-dev libmatio-dev libssl-dev
          pybind11-dev python3-dev python3-numpy python3-pytest
          libopenmpi-dev openmpi-bin
          chromium  # the HTML report's browser test (headless)
          clang libclang-rt-14-dev)  # fuzz/: libFuzzer and the sanitizer runtimes

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  SUDO=""
  [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  echo "setup: installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}"
fi

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$(nproc)"
echo "setup: built build/tools/triadcal"
