#!/usr/bin/env python3
"""Wall time of `triadcal diagnose` against one `triadcal fit` of the same run.

usage: diagnose_speed.py [--repeats N] [--keep DIR] [--rate HZ]
       diagnose_speed.py --real [--runs slow,medium,fast] [--repeats N] [--keep DIR]

Simulates the paper's 90-s run (examples/paper-experiment3/scenario.yaml), clean
and with one undeclared effect added under `effects:`, and times `fit` and
`diagnose` side by side on each (median of N runs, one process at a time).
--rate replaces the example's 1 kHz (e.g. 50: the paper profile of issue 12). The
issue-12 target: diagnose <= 3x one fit. Also prints how many candidates the
score tests sent to a refit and what was selected.

--real times the three real roll runs (examples/single-axis-roll/{slow,medium,
fast}.yaml) instead; they need the shared data folder and are skipped without
it. Also prints whether the fit converged and the time offset found.
"""
import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
BIN = os.environ.get("TRIADCAL", os.path.join(HERE, "..", "build", "tools", "triadcal"))
BASE = os.path.join(HERE, "..", "examples", "paper-experiment3", "scenario.yaml")

CASES = {
    "clean": "",
    "angle_latency": "angle_latency: {tau_ms: 2.0}",
    "thermal_drift": "thermal_drift: {rate_x_mV_per_min: 0.18, rate_y_mV_per_min: -0.12, "
                     "rate_z_mV_per_min: 0.15}",
    "size_effect": "size_effect: {ry_x_mm: 29.0, rz_y_mm: -29.0}",
}


def timed(cmd, ok=(0,)):
    t0 = time.perf_counter()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode not in ok:
        sys.exit(f"{' '.join(cmd)}: exit {p.returncode}: {p.stderr.strip()[-400:]}")
    return time.perf_counter() - t0


REAL = os.path.join(HERE, "..", "examples", "single-axis-roll")


def real(a, work):
    print(f"real roll runs ({REAL}), median of {a.repeats}")
    print(f"{'run':8s} {'fit s':>7s} {'conv':>5s} {'diag s':>7s} {'ratio':>6s} {'refits':>6s}"
          f"  {'tau ms':>14s}  selected")
    ratios = []
    for name in a.runs.split(","):
        run = os.path.join(REAL, name + ".yaml")
        fit_out = os.path.join(work, name + "_fit.json")
        diag_out = os.path.join(work, name + "_diagnose.json")
        # Exit 4: the fit did not converge; timed all the same, and said.
        fit_cmd = [BIN, "fit", run, "-q", "--force", "-o", fit_out]
        diag_cmd = [BIN, "diagnose", run, "-q", "--force", "-o", diag_out]
        probe = subprocess.run([BIN, "mounting", run], capture_output=True, text=True)
        if probe.returncode != 0 and ("shared data folder not found" in probe.stderr
                                     or "data: no such file" in probe.stderr):
            print(f"{name:8s} skipped: {probe.stderr.strip()[:160]}")
            continue
        fits, diags = [], []
        for _ in range(a.repeats):
            fits.append(timed(fit_cmd, ok=(0, 4)))
            diags.append(timed(diag_cmd))
        conv = json.load(open(fit_out))["converged"]
        out = json.load(open(diag_out))
        refits = sum(1 for t in out["tests"] if t.get("refit"))
        tau = out.get("after", {}).get("parameters", {}).get("angle_latency.tau")
        tau_s = f"{tau['value']:.3f}+-{tau['sigma']:.3f}" if tau and tau.get("sigma") else "-"
        f, g = statistics.median(fits), statistics.median(diags)
        ratios.append(g / f)
        print(f"{name:8s} {f:7.1f} {str(conv):>5s} {g:7.1f} {g / f:6.2f} {refits:6d}  {tau_s:>14s}"
              f"  {','.join(out['selected']) or '-'}")
    if ratios:
        print(f"largest ratio {max(ratios):.2f} (target <= 3)")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--keep")
    ap.add_argument("--rate", type=float, help="sampling rate [Hz] instead of the example's")
    ap.add_argument("--real", action="store_true", help="the three real roll runs instead")
    ap.add_argument("--runs", default="slow,medium,fast", help="with --real: which of them")
    a = ap.parse_args()
    work = a.keep or tempfile.mkdtemp(prefix="diagnose_speed_")
    os.makedirs(work, exist_ok=True)
    if a.real:
        return real(a, work)
    print(f"{BASE} at {a.rate or 'its own'} Hz, median of {a.repeats}")
    print(f"{'case':15s} {'fit s':>7s} {'diag s':>7s} {'ratio':>6s} {'refits':>6s}  selected")
    ratios = []
    for case, effect in CASES.items():
        d = os.path.join(work, case)
        os.makedirs(d, exist_ok=True)
        s = open(BASE).read()
        if a.rate:
            s = re.sub(r"(?m)^(\s*rate_hz:)\s*[0-9.]+", rf"\g<1> {a.rate:g}", s)
        if effect:
            s += f"\neffects:\n  {effect}\n"
        open(os.path.join(d, "scenario.yaml"), "w").write(s)
        subprocess.run([BIN, "simulate", os.path.join(d, "scenario.yaml"), "-o", d], check=True,
                       capture_output=True)
        run = os.path.join(d, "run.yaml")
        fit_cmd = [BIN, "fit", run, "-o", os.path.join(d, "fit.json")]
        diag_cmd = [BIN, "diagnose", run, "-o", os.path.join(d, "diagnose.json")]
        fits, diags = [], []
        for _ in range(a.repeats):
            fits.append(timed(fit_cmd))
            diags.append(timed(diag_cmd))
        out = json.load(open(os.path.join(d, "diagnose.json")))
        refits = sum(1 for t in out["tests"] if t.get("refit"))
        f, g = statistics.median(fits), statistics.median(diags)
        ratios.append(g / f)
        print(f"{case:15s} {f:7.2f} {g:7.2f} {g / f:6.2f} {refits:6d}  "
              f"{','.join(out['selected']) or '-'}")
    print(f"largest ratio {max(ratios):.2f} (target <= 3)")


if __name__ == "__main__":
    sys.exit(main())
