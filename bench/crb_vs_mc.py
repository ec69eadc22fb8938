#!/usr/bin/env python3
"""Batch sigma and Monte-Carlo scatter against the Cramer-Rao bound.

usage: crb_vs_mc.py CRB_OUT.json RUN_DIR...
CRB_OUT.json is `fit` on a noise-free run of the scenario that declares the
true noise: its covariance is the inverse Fisher information of the same model
(priors included) at the truth, i.e. the CRB. Each RUN_DIR holds truth.json and
out.json of a noisy seed. Prints per parameter: CRB sigma, mean batch sigma,
Monte-Carlo scatter (RMS of estimate - truth), and the ratios; exits 1 when a
batch sigma is more than 15 % from the CRB (env CRB_TOL).
"""
import json
import math
import os
import sys


def main():
    tol = float(os.environ.get("CRB_TOL", "0.15"))
    crb = json.load(open(sys.argv[1]))["parameters"]
    dirs = sys.argv[2:]
    err = {}
    sig = {}
    for d in dirs:
        truth = json.load(open(os.path.join(d, "truth.json")))["parameters"]
        out = json.load(open(os.path.join(d, "out.json")))["parameters"]
        for name, p in out.items():
            if name in truth:
                err.setdefault(name, []).append(p["value"] - truth[name])
                sig.setdefault(name, []).append(p["sigma"])
    bad = []
    n = len(dirs)
    # The scatter of N draws estimates sigma to about 1/sqrt(2N) relative.
    print(f"{'parameter':10s} {'CRB':>10s} {'batch sig':>10s} {'MC scatter':>10s} "
          f"{'sig/CRB':>8s} {'MC/CRB':>8s}  unit   (N={n}; MC/CRB has +-{100/math.sqrt(2*n):.0f}% "
          f"sampling error)")
    for name, c in crb.items():
        if name not in err:
            continue
        s = sum(sig[name]) / len(sig[name])
        mc = math.sqrt(sum(e * e for e in err[name]) / len(err[name]))
        r1 = s / c["sigma"]
        r2 = mc / c["sigma"]
        flag = "" if abs(r1 - 1) <= tol else "  <-- batch sigma off the CRB"
        if flag:
            bad.append(name)
        print(f"{name:10s} {c['sigma']:10.4g} {s:10.4g} {mc:10.4g} {r1:8.3f} {r2:8.3f}  "
              f"{c['unit']}{flag}")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
