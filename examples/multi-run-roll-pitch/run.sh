#!/usr/bin/env bash
# The joint calibration of the real roll and pitch runs, with the loop's effects
# (angle latency per run, a zero drift per run); needs the shared data folder and
# skips cleanly without it.
#   examples/multi-run-roll-pitch/run.sh [OUTDIR]     (default out/multi-run-roll-pitch)
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
bin="${TRIADCAL:-$here/../../build/tools/triadcal}"
out="${1:-out/multi-run-roll-pitch}"
# The shared folder as triadcal finds it: $TRIADCAL_SHARED, or `shared` beside a
# parent of this folder.
shared="${TRIADCAL_SHARED:-}"
if [ -z "$shared" ]; then
  d="$here"
  while [ "$d" != "/" ]; do
    if [ -d "$d/shared" ]; then shared="$d/shared"; break; fi
    d="$(dirname "$d")"
  done
fi
if [ -z "$shared" ] || [ ! -f "$shared/data/real/single-axis-encoder/raw_pitch_medium.mat" ]; then
  echo "multi-run-roll-pitch: the shared data folder is not here (set TRIADCAL_SHARED); skipped"
  exit 0
fi
mkdir -p "$out"
# dpsi (the shaft's tilt) is held in every run: a single-axis run ties it to
# the shaft reading's zero offset and cross terms, and the slow roll run's fit
# alone slides along that family for ever (docs/method.md).
"$bin" fit "$here/runs.yaml" --effects angle_latency,thermal_drift --hold dpsi \
  -o "$out/joint.json" | tee "$out/joint.txt"
