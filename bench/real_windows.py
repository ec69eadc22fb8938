#!/usr/bin/env python3
"""Pieces of the real runs as runs the project has not fitted: each real run
of examples/ cut with `time_range_s` into windows, each window through `fit`
(or another command). Prints per window the exit code, wall time, whether the
fit converged in how many steps, and the scale factors with their sigma or
what the run did not determine.

usage: bench/real_windows.py [COMMAND]      (default fit; e.g. diagnose)

Needs the shared data folder (skips without it). The windows' run files are
written beside the examples' (they name the shared data relative to them) and
removed after each command.
"""
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BIN = os.environ.get("TRIADCAL", os.path.join(ROOT, "build", "tools", "triadcal"))
SHARED = os.path.join(ROOT, "..", "shared", "data", "real")
RUNS = {
    "slow": "examples/single-axis-roll/slow.yaml",
    "medium": "examples/single-axis-roll/medium.yaml",
    "fast": "examples/single-axis-roll/fast.yaml",
    "pitch": "examples/multi-run-roll-pitch/pitch.yaml",
    "slow_gyro": "examples/single-axis-roll/slow_gyro.yaml",
}
WINDOWS = [(0, 60), (0, 120), (0, 300), (200, 500), (400, 1000), (900, 1500)]


def scale_factors(out):
    texts = []
    for k in ("Kx", "Ky", "Kz"):
        v = out["parameters"].get(k, {})
        if v.get("determined", True) and v.get("sigma") is not None:
            texts.append(f"{k} {v['value']:.1f} +- {v['sigma']:.2g}")
        else:
            texts.append(f"{k} {v.get('value', float('nan')):.1f} (not determined)")
    return ", ".join(texts)


def main():
    command = sys.argv[1] if len(sys.argv) > 1 else "fit"
    if not os.path.isdir(SHARED) and not os.environ.get("TRIADCAL_SHARED"):
        print("real_windows: the shared data folder is absent; skipped")
        return 0
    work = os.path.join("/tmp", f"triadcal_real_windows_{os.getpid()}")
    os.makedirs(work, exist_ok=True)
    failures = 0
    for name, rel in RUNS.items():
        src_path = os.path.join(ROOT, rel)
        src = open(src_path).read()
        for a, b in WINDOWS:
            window = os.path.join(os.path.dirname(src_path), f".window_{name}_{a}_{b}.yaml")
            out = os.path.join(work, f"{name}_{a}_{b}_{command}.json")
            with open(window, "w") as f:
                f.write(src + f"\ntime_range_s: [{a}, {b}]\n")
            t0 = time.time()
            try:
                p = subprocess.run([BIN, command, window, "-o", out, "--force", "-q"],
                                   capture_output=True, text=True)
            finally:
                os.remove(window)
            line = f"{name:10s} [{a:4d}, {b:4d}] s  {command} exit {p.returncode}  {time.time() - t0:5.2f} s"
            if p.returncode in (0, 4) and os.path.exists(out):
                j = json.load(open(out))
                if command == "fit":
                    line += (f"  converged {j['converged']} in {j['iterations']['steps']} steps; "
                             + scale_factors(j))
                elif command == "diagnose":
                    line += f"  selected {','.join(j.get('selected', [])) or '-'}"
                failures += 0 if j.get("converged", True) else 1
            else:
                errors = [l for l in p.stderr.splitlines() if "error" in l]
                line += "  " + (errors[-1] if errors else p.stderr.strip()[-200:])
                failures += 1
            print(line, flush=True)
    print(f"\n{failures} window(s) not converged or refused")
    return 0


if __name__ == "__main__":
    sys.exit(main())
