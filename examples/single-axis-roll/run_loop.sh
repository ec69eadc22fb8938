#!/usr/bin/env bash
# Closing the loop on the real single-axis runs (needs the shared data folder):
# diagnose each speed, then compare the estimates across the three speeds, the
# error measure of a real run without truth.
#   examples/single-axis-roll/run_loop.sh [OUTDIR] [--noise-auto]
#     (default OUTDIR out/single-axis-roll; --noise-auto replaces each run's
#      declared noise_mV by `auto`: docs/real-data.md compares the two)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${TRIADCAL:-$here/../../build/tools/triadcal}"
out="${1:-out/single-axis-roll}"
if [ $# -gt 2 ] || { [ $# -eq 2 ] && [ "$2" != "--noise-auto" ]; }; then
  echo "run_loop.sh: unknown argument '${*:2}' (usage: run_loop.sh [OUTDIR] [--noise-auto])" >&2
  exit 2
fi
mkdir -p "$out"
for s in slow medium fast; do
  yaml="$here/$s.yaml"
  if [ "${2:-}" = "--noise-auto" ]; then
    yaml="$out/$s-noise-auto.yaml"
    sed 's/^  noise_mV: .*/  noise_mV: auto/' "$here/$s.yaml" > "$yaml"
  fi
  "$bin" diagnose "$yaml" -o "$out/$s.json" > "$out/$s.txt"
  head -1 "$out/$s.txt"
done
python3 "$here/consistency.py" "$out"/slow.json "$out"/medium.json "$out"/fast.json
