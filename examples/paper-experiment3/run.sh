#!/usr/bin/env bash
# The main job on the bundled example: simulate the paper's experiment 3 and
# estimate everything back with the batch solver (`fit`), then say how far the
# estimates are from the truth in units of their sigma.
#   examples/paper-experiment3/run.sh [OUTDIR]      (default out/paper-experiment3)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$here/../.."
bin="${TRIADCAL:-$root/build/tools/triadcal}"
out="${1:-out/paper-experiment3}"
mkdir -p "$out"
"$bin" simulate "$here/scenario.yaml" -o "$out"
"$bin" fit "$out/run.yaml" -o "$out/fit.json" --residuals "$out/fit_residuals.csv"
python3 - "$out" <<'PY' || true
import json, sys
d = sys.argv[1]
truth = json.load(open(d + "/truth.json"))["parameters"]
est = json.load(open(d + "/fit.json"))["parameters"]
z = {n: (p["value"] - truth[n]) / p["sigma"] for n, p in est.items() if n in truth}
worst = max(z, key=lambda n: abs(z[n]))
rms = (sum(v * v for v in z.values()) / len(z)) ** 0.5
print(f"against the truth: RMS (estimate - truth)/sigma over {len(z)} parameters {rms:.2f}, "
      f"largest {z[worst]:+.2f} ({worst})")
PY
