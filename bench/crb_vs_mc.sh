#!/usr/bin/env bash
# Batch sigma and Monte-Carlo scatter against the Cramer-Rao bound of the same
# model, on the Monte-Carlo scenario (paper experiment 3, 100 Hz, 2 mV, 15").
#   bench/crb_vs_mc.sh [N]        (default 30 seeds)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${TRIADCAL:-$here/../build/tools/triadcal}"
n="${1:-30}"
scen="$here/scenarios/paper-mc.yaml"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
# The CRB: the same scenario without noise (and without the truth spread),
# declaring the true noise, fitted at the truth.
python3 - "$scen" "$work/crb.yaml" <<'PY'
import re, sys
s = open(sys.argv[1]).read()
s = re.sub(r"truth_spread:\n(  .*\n)+", "", s)
s = s.replace("noise:\n", "noise:\n  accel_mV: 0\n  angle_arcsec: 0\nnoise_declared_unused:\n", 1)
s = s.replace("noise_declared_unused:\n", "", 1)
# drop the original noise values (the first ones win otherwise)
lines, out, in_noise, seen = s.split("\n"), [], False, set()
for l in lines:
    if l.startswith("noise:"):
        in_noise = True; out.append(l); continue
    if in_noise and l.startswith("  ") and ":" in l and not l.strip().startswith("#"):
        k = l.strip().split(":")[0]
        if k in seen: continue
        seen.add(k)
    elif in_noise and not l.startswith("  ") and l.strip():
        in_noise = False
    out.append(l)
s = "\n".join(out)
s = s.replace("    # noise_mV: taken from noise.accel_mV", "    noise_mV: 2.0")
s = s.replace("    # angle_noise_arcsec: taken from noise.angle_arcsec (15\")", "    angle_noise_arcsec: 15")
open(sys.argv[2], "w").write(s)
PY
"$bin" simulate "$work/crb.yaml" -o "$work/crb" > /dev/null
"$bin" fit "$work/crb/run.yaml" -o "$work/crb/out.json" > /dev/null
for seed in $(seq 1 "$n"); do
  d="$work/seed$seed"
  "$bin" simulate "$scen" -o "$d" --seed "$seed" > /dev/null
  "$bin" fit "$d/run.yaml" -o "$d/out.json" > /dev/null
done
python3 "$here/crb_vs_mc.py" "$work/crb/out.json" "$work"/seed*
