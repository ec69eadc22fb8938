#!/usr/bin/env bash
# Builds the libFuzzer targets (clang, ASan + UBSan) in build-fuzz and runs each
# for SECONDS (default 60) on a working copy of its seed corpus fuzz/corpus/<target>.
# Prints the executions per target; exits non-zero on any finding (a crash, a
# sanitizer report, an exception other than triadcal's InputError, a timeout).
# Usage: fuzz/run.sh [SECONDS]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds="${1:-60}"
targets=(csv_reader run_yaml scenario constraint calibration_json mat_reader apply)
flags="-g -O1 -fno-omit-frame-pointer -fsanitize=fuzzer-no-link,address,undefined"
flags+=" -fno-sanitize-recover=undefined -DEIGEN_MALLOC_ALREADY_ALIGNED=1"
launcher=()
command -v ccache > /dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
mkdir -p build-fuzz
cmake -S . -B build-fuzz -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_CXX_FLAGS="$flags" "${launcher[@]}" \
  -DTRIADCAL_FUZZ=ON -DTRIADCAL_BUILD_TESTS=OFF > build-fuzz/build.log
cmake --build build-fuzz -j"${FUZZ_JOBS:-2}" --target "${targets[@]/#/fuzz_}" >> build-fuzz/build.log
status=0
for t in "${targets[@]}"; do
  work="build-fuzz/corpus/$t"
  mkdir -p "$work" "build-fuzz/findings/$t"
  cp -n fuzz/corpus/"$t"/* "$work"/ 2> /dev/null || true
  log="build-fuzz/$t.log"
  # matio's own leaks on damaged files (fuzz/lsan_matio.supp), with full stacks.
  asan="${ASAN_OPTIONS:-}" lsan="${LSAN_OPTIONS:-}"
  if [ "$t" = mat_reader ]; then
    asan="$asan:fast_unwind_on_malloc=0"
    lsan="suppressions=$PWD/fuzz/lsan_matio.supp"
  fi
  if ! UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 ASAN_OPTIONS="$asan" LSAN_OPTIONS="$lsan" \
      "build-fuzz/fuzz/fuzz_$t" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 \
      -print_final_stats=1 -artifact_prefix="build-fuzz/findings/$t/" "$work" > "$log" 2>&1; then
    echo "fuzz: $t: FINDING (see $log and build-fuzz/findings/$t/)"
    grep -m 5 -E "ERROR|runtime error|uncaught|terminate" "$log" || true
    status=1
  fi
  execs=$(grep -m1 -o "stat::number_of_executed_units: [0-9]*" "$log" | grep -o "[0-9]*$" || echo "?")
  echo "fuzz: $t: $execs executions in ${seconds} s, corpus $(ls "$work" | wc -l) files"
done
exit $status
