#!/usr/bin/env bash
# Closing the loop on the real single-axis runs (needs the shared data folder):
# diagnose each speed, then compare the estimates across the three speeds, the
# error measure of a real run without truth.
#   examples/single-axis-roll/run_loop.sh [OUTDIR]      (default out/single-axis-roll)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${TRIADCAL:-$here/../../build/tools/triadcal}"
out="${1:-out/single-axis-roll}"
mkdir -p "$out"
for s in slow medium fast; do
  "$bin" diagnose "$here/$s.yaml" -o "$out/$s.json" > "$out/$s.txt"
  head -1 "$out/$s.txt"
done
python3 "$here/consistency.py" "$out"/slow.json "$out"/medium.json "$out"/fast.json
