#!/usr/bin/env python3
"""Normalised-error statistics of estimator outputs against simulated truth.

usage: mc_stats.py SECTION RUN_DIR...   (SECTION: ekf, rts, or "" for a top-level
"parameters" object). Each RUN_DIR holds truth.json and out.json. Prints, per
parameter, the mean and RMS of (estimate - truth) / sigma over the runs, and the
mean sigma; exits 1 when a parameter's RMS is outside [lo, hi] (env MC_LO, MC_HI).
"""
import json
import math
import os
import sys


def main():
    section = sys.argv[1]
    dirs = sys.argv[2:]
    lo = float(os.environ.get("MC_LO", "0.7"))
    hi = float(os.environ.get("MC_HI", "1.3"))
    z = {}
    sig = {}
    units = {}
    for d in dirs:
        truth = json.load(open(os.path.join(d, "truth.json")))["parameters"]
        out = json.load(open(os.path.join(d, "out.json")))
        params = (out[section] if section else out)["parameters"]
        for name, p in params.items():
            if name not in truth or not p.get("estimable", True):
                continue
            z.setdefault(name, []).append((p["value"] - truth[name]) / p["sigma"])
            sig.setdefault(name, []).append(p["sigma"])
            units[name] = p["unit"]
    bad = []
    print(f"{'parameter':12s} {'mean z':>8s} {'rms z':>8s} {'mean sigma':>12s}  unit   (N={len(dirs)})")
    for name in z:
        v = z[name]
        mean = sum(v) / len(v)
        rms = math.sqrt(sum(x * x for x in v) / len(v))
        flag = "" if lo <= rms <= hi else "  <-- outside [%g, %g]" % (lo, hi)
        if flag:
            bad.append(name)
        print(f"{name:12s} {mean:8.3f} {rms:8.3f} {sum(sig[name])/len(sig[name]):12.4g}  {units[name]}{flag}")
    allz = [x for v in z.values() for x in v]
    print(f"all parameters: rms z = {math.sqrt(sum(x*x for x in allz)/len(allz)):.3f}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
