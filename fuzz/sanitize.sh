#!/usr/bin/env bash
# Builds triadcal and its tests with AddressSanitizer + UndefinedBehaviorSanitizer
# in build-asan (GCC, as the release build) and runs the whole test suite there.
# -DEIGEN_MALLOC_ALREADY_ALIGNED=1: GCC defines __SANITIZE_ADDRESS__ under ASan,
# which makes Eigen switch from malloc to its hand-made aligned allocator in our
# code only; Debian's libceres (built without ASan) keeps malloc, so an Eigen
# object allocated inside libceres and freed in ours (GradientChecker's
# ProbeResults) reads before its block. The define restores the release
# build's choice (glibc malloc is 16-byte aligned on x86-64); see
# docs/reliability.md.
# Usage: fuzz/sanitize.sh [ctest arguments, e.g. -R CliInputErrors]
set -euo pipefail
cd "$(dirname "$0")/.."
flags="-O1 -g -fno-omit-frame-pointer -fsanitize=address,undefined"
flags+=" -fno-sanitize-recover=undefined -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  "${launcher[@]}" > /dev/null
cmake --build build-asan -j2
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
ctest --test-dir build-asan --output-on-failure -j2 "$@"
