#!/usr/bin/env bash
# Wall time and peak memory of the estimators on 90 s and 40 min runs at 1 kHz
# (the paper's experiment 3 scenario), measured in the same run on this machine.
#   bench/run_benchmarks.sh [WORKDIR]
# Prints a Markdown table. Uses build/tools/triadcal.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${TRIADCAL:-$here/../build/tools/triadcal}"
work="${1:-$(mktemp -d)}"
mkdir -p "$work"
"$bin" simulate "$here/../examples/paper-experiment3/scenario.yaml" -o "$work/90s" > /dev/null
"$bin" simulate "$here/scenarios/paper-40min.yaml" -o "$work/40min" > /dev/null
echo "| run, command | wall s | peak MB | exit |"
echo "|---|---|---|---|"
for run in 90s 40min; do
  for cmd in ${BENCH_COMMANDS:-filter fit}; do
    python3 "$here/measure.py" "$run $cmd" -- "$bin" "$cmd" "$work/$run/run.yaml" -o "$work/$run/$cmd.json"
  done
done
