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
#
# Four groups of tests are run apart or not at all (docs/reliability.md):
#   - the statistical tests (label statistical, tests/CMakeLists.txt):
#     GyroTerm.NormalisedErrorsOverTwentySeeds, 20 fits (173 s under ASan, 20 s
#     without), and CliGyroEffectsSeeds.EachGyroEffectOverTenSeeds, 20
#     simulations and fits: their paths, the fit with a gyro and its effects,
#     run under ASan in GyroTerm.FitRecoversTheGyroWithinItsSigma,
#     SharedTimeOffsetIsEstimated and FitRecoversEachGyroEffect;
#   - the two MPI tests (OnTwoMpiRanks): Open MPI's own allocations, suppressed
#     by fuzz/lsan_mpi.supp with full unwinding;
#   - python_pytest: the system python3 is not built with ASan, so the runtime
#     is preloaded and pytest runs directly (not under ctest, which must not
#     get the preload); fuzz/lsan_python.supp;
#   - the install tests (label install: installed_consumer builds an outside
#     project against the installed library without the sanitizer flags;
#     installed_python imports the sanitized module into python3): not run here.
# Usage: fuzz/sanitize.sh            (the whole suite)
#        fuzz/sanitize.sh -R NAME    (ctest arguments: some tests only)
set -euo pipefail
cd "$(dirname "$0")/.."
flags="-fno-omit-frame-pointer -fsanitize=address,undefined"
flags+=" -fno-sanitize-recover=undefined -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
# Sources that change while the build runs leave objects compiled from the old
# headers but newer than them, which ninja then never rebuilds: refuse that.
state() { git rev-parse HEAD 2> /dev/null; git status --porcelain 2> /dev/null | grep -v '^??' || true; }
before="$(state)"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" -DCMAKE_CXX_FLAGS="$flags" -DCMAKE_EXE_LINKER_FLAGS="-fsanitize=address,undefined" \
  "${launcher[@]}" > /dev/null
cmake --build build-asan -j2
echo "sanitize: build-asan built in ${SECONDS} s"
if [ "$(state)" != "$before" ]; then
  echo "fuzz/sanitize.sh: the sources changed during the build; build-asan may hold stale objects (touch the changed headers and run again)" >&2
  exit 1
fi
supp="$PWD/fuzz"
export ASAN_OPTIONS=detect_leaks=1:abort_on_error=0:strict_string_checks=1
export UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1
if [ $# -gt 0 ]; then
  ctest --test-dir build-asan --output-on-failure -j2 "$@"
  exit
fi
status=0
ctest --test-dir build-asan --output-on-failure -j2 \
  -LE '^(install|statistical)$' \
  -E 'OnTwoMpiRanks|^python_pytest$' || status=1
ASAN_OPTIONS=$ASAN_OPTIONS:fast_unwind_on_malloc=0 LSAN_OPTIONS=suppressions=$supp/lsan_mpi.supp \
  ctest --test-dir build-asan --output-on-failure -R 'OnTwoMpiRanks' || status=1
echo "python module under ASan (pytest, runtime preloaded):"
LD_PRELOAD="$(gcc -print-file-name=libasan.so):$(gcc -print-file-name=libubsan.so)" \
  LSAN_OPTIONS=suppressions=$supp/lsan_python.supp PYTHONPATH=build-asan/python \
  PYTHONDONTWRITEBYTECODE=1 TRIADCAL_BIN=build-asan/tools/triadcal TRIADCAL_SOURCE_DIR="$PWD" \
  /usr/bin/python3 -m pytest -q -p no:cacheprovider python/tests || status=1
echo "sanitize: build and suite in ${SECONDS} s"
exit $status
