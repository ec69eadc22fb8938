#!/usr/bin/env bash
# Multi-run accuracy over many seeds (issue 13, docs/multi-run.md): two
# single-axis runs with different shafts, and four runs at -20..40 degC with
# one remounted. Runs the disabled tests JointFitBench.* of
# solvers/multirun/joint_solver_test.cpp; prints the RMS of (estimate - truth)
# / sigma and how often a run is named inconsistent.
# Usage: bench/multirun_accuracy.sh [seeds, default 20]   (build first: ./setup.sh)
set -euo pipefail
cd "$(dirname "$0")/.."
TRIADCAL_BENCH_SEEDS="${1:-20}" build/tests/triadcal_tests \
  --gtest_also_run_disabled_tests --gtest_filter='JointFitBench.*' | grep -E "seeds|OK|FAILED"
