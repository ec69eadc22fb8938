#!/usr/bin/env bash
# The paper's Table 2 columns on one simulated sensor: the standard static
# method (40 min of bench positions) next to the quasi-harmonic batch (90 s of
# the paper's profile), each with its sigma. The simulation and both fits are
# the test StaticVsQuasiHarmonic.Table2 (solvers/static/static_method_test.cpp); this
# prints its table.
#   bench/static_vs_quasiharmonic.sh [BUILD_DIR]      (default build)
set -euo pipefail
root="$(cd "$(dirname "$0")/.." && pwd)"
build="${1:-$root/build}"
"$build/tests/triadcal_tests" --gtest_filter='StaticVsQuasiHarmonic.Table2' |
  sed -n '/^Simulated/,/^static: chi2/p'
