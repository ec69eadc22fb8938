#!/usr/bin/env python3
"""Two triadcal binaries on the same commands, alternated: wall-time medians and fit steps.

usage: bench/ab.py [--repeats N] BIN_A BIN_B RUN.yaml [RUN.yaml ...] [-- COMMAND ARGS]

For each run, runs `BIN COMMAND RUN -o OUT --force -q ARGS` (COMMAND `fit` by
default) with A and B in turn, N times each (default 5), one command at a
time, so that a machine's load falls on both alike; prints the median wall
time of each, their ratio, and the steps of a fit's OUT (`iterations.steps`).
Exit 1 when a command fails. For changes to the solver, e.g.

    git stash; cmake --build build; cp build/tools/triadcal /tmp/before; git stash pop
    cmake --build build
    bench/ab.py /tmp/before build/tools/triadcal examples/single-axis-roll/*.yaml
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time


def run_once(binary, command, run, out, extra):
    cmd = [binary, command, run, "-o", out, "--force", "-q"] + extra
    start = time.monotonic()
    try:
        done = subprocess.run(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    except OSError as e:
        sys.exit(f"ab.py: cannot run {binary}: {e.strerror}")
    wall = time.monotonic() - start
    if done.returncode not in (0, 4):  # 4: fit did not converge (said in OUT)
        sys.exit(f"ab.py: {' '.join(cmd)} exited {done.returncode}: "
                 f"{done.stderr.strip().splitlines()[-1] if done.stderr.strip() else ''}")
    steps = None
    try:
        with open(out) as f:
            steps = json.load(f).get("iterations", {}).get("steps")
    except (OSError, ValueError, AttributeError):
        pass
    return wall, steps


def main():
    argv = sys.argv[1:]
    extra = []
    if "--" in argv:
        i = argv.index("--")
        argv, extra = argv[:i], argv[i + 1:]
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("a")
    p.add_argument("b")
    p.add_argument("runs", nargs="+")
    a = p.parse_args(argv)
    if a.repeats < 1:
        sys.exit("ab.py: --repeats must be at least 1")
    command = "fit"
    if extra and not extra[0].startswith("-"):
        command, extra = extra[0], extra[1:]
    print(f"| run | A s | B s | B/A | A steps | B steps |  (A {a.a}, B {a.b}, {command}, "
          f"medians of {a.repeats})")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as work:
        for run in a.runs:
            times = {a.a: [], a.b: []}
            steps = {}
            for _ in range(a.repeats):
                for binary in (a.a, a.b):
                    out = os.path.join(work, "a.json" if binary == a.a else "b.json")
                    wall, s = run_once(binary, command, run, out, extra)
                    times[binary].append(wall)
                    steps[binary] = s
            ta, tb = statistics.median(times[a.a]), statistics.median(times[a.b])
            shown = {b: "–" if steps[b] is None else steps[b] for b in steps}
            print(f"| {run} | {ta:.3f} | {tb:.3f} | {tb / ta:.2f} | {shown[a.a]} | {shown[a.b]} |")


if __name__ == "__main__":
    main()
