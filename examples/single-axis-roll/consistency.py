#!/usr/bin/env python3
"""Consistency of the estimates across the three speeds, before and after the
loop: for each parameter estimated in every run, the spread of the values
against their sigma (chi-square of the values about their weighted mean, per
degree of freedom; ~1 when the runs agree within their sigma).

usage: consistency.py slow.json medium.json fast.json   (diagnose outputs)
"""
import json
import math
import sys


def table(outs, state):
    names = [n for n, p in outs[0][state]["parameters"].items()
             if all(n in o[state]["parameters"] and o[state]["parameters"][n]["estimable"]
                    for o in outs)]
    print(f"\n{state}: {'parameter':24s} " + " ".join(f"{'value':>12s} {'sigma':>8s}" for _ in outs)
          + f" {'chi2/dof':>9s}  unit")
    worst = []
    for n in names:
        ps = [o[state]["parameters"][n] for o in outs]
        w = [1 / p["sigma"] ** 2 for p in ps]
        mean = sum(wi * p["value"] for wi, p in zip(w, ps)) / sum(w)
        chi2 = sum(((p["value"] - mean) / p["sigma"]) ** 2 for p in ps) / (len(ps) - 1)
        worst.append(chi2)
        print(f"{'':8s}{n:24s} " + " ".join(f"{p['value']:12.5g} {p['sigma']:8.3g}" for p in ps)
              + f" {chi2:9.2f}  {ps[0]['unit']}")
    print(f"{'':8s}median chi2/dof across parameters: {sorted(worst)[len(worst) // 2]:.2f}")


def main():
    outs = [json.load(open(f)) for f in sys.argv[1:]]
    for f, o in zip(sys.argv[1:], outs):
        print(f"{f}: selected {o['selected']}; residual accel RMS before/after [mg]: " +
              ", ".join(f"{k.split()[-1]} {o['before']['residual_rms'][k]:.2f}/{o['after']['residual_rms'][k]:.2f}"
                        for k in o["before"]["residual_rms"] if k.startswith("accel")))
    table(outs, "before")
    table(outs, "after")


if __name__ == "__main__":
    main()
