#!/usr/bin/env bash
# Monte Carlo of an estimator against simulated truth.
#   bench/monte_carlo.sh COMMAND SECTIONS SCENARIO.yaml N [extra args for COMMAND]
# SECTIONS: the OUT sections holding "parameters", e.g. "ekf rts" for filter,
# "-" for the top level (fit).
# e.g. bench/monte_carlo.sh filter "ekf rts" bench/scenarios/paper-mc.yaml 30
#      bench/monte_carlo.sh fit - bench/scenarios/paper-mc.yaml 100
# Simulates N runs (seeds 1..N) into a temporary folder, runs
# `triadcal COMMAND run.yaml -o out.json` on each, and prints the normalised
# errors per parameter (bench/mc_stats.py). Uses build/tools/triadcal.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${TRIADCAL:-$here/../build/tools/triadcal}"
cmd="$1"; section="$2"; scenario="$3"; n="$4"; shift 4
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
start=$(date +%s.%N)
for seed in $(seq 1 "$n"); do
  d="$work/seed$seed"
  "$bin" simulate "$scenario" -o "$d" --seed "$seed" > /dev/null
  "$bin" "$cmd" "$d/run.yaml" -o "$d/out.json" "$@" > /dev/null
done
end=$(date +%s.%N)
echo "$cmd on $n runs of $(basename "$scenario"): $(python3 -c "print(round($end - $start, 1))") s in all"
for s in $section; do
  [ "$s" = "-" ] && s=""
  echo "== section: ${s:-top-level parameters}"
  python3 "$here/mc_stats.py" "$s" "$work"/seed* || status=1
done
exit "${status:-0}"
