#!/usr/bin/env bash
# The main job on the bundled example: simulate the paper's experiment 3, then
# estimate everything back with the paper's filter (EKF + RTS smoother).
#   examples/paper-experiment3/run.sh [OUTDIR]      (default out/paper-experiment3)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$here/../.."
bin="${TRIADCAL:-$root/build/tools/triadcal}"
out="${1:-out/paper-experiment3}"
mkdir -p "$out"
"$bin" simulate "$here/scenario.yaml" -o "$out"
"$bin" filter "$out/run.yaml" -o "$out/filter.json" --series "$out/filter_series.csv"
python3 - "$out" <<'PY' || true
import json, sys
d = sys.argv[1]
truth = json.load(open(d + "/truth.json"))["parameters"]
est = json.load(open(d + "/filter.json"))["rts"]["parameters"]
worst = max(abs(p["value"] - truth[n]) / p["sigma"] for n, p in est.items() if n in truth)
print(f"largest |RTS estimate - truth| / sigma over {len(est)} parameters: {worst:.2f}")
PY
