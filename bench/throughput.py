#!/usr/bin/env python3
"""Throughput of triadcal on this machine: fits of the paper's 90-s run and
Monte Carlo seeds, on 1 rank and on 2 MPI ranks, measured in the same run.

usage: bench/throughput.py [--fits K] [--seeds N] [--repeat R] [--workdir DIR]
       (TRIADCAL=path/to/triadcal to use another binary)

What it runs (every rank single-threaded, so 1 rank = 1 core):
  fit    examples/paper-experiment3 (90 s at 1 kHz, 90 000 samples), once
         alone for the per-run wall time and peak memory, then K copies
         through `batch --threads 1` on 1 rank and `mpirun -n 2 batch
         --threads 1`: runs per second.
  seed   bench/scenarios/paper-mc.yaml (90 s at 100 Hz through EKF, RTS and
         batch), `montecarlo -n N --threads 1` on 1 rank and on 2 ranks:
         seeds per second (the one-off CRB, about 0.1 s, included).
Each 1-rank/2-rank pair is repeated R times, interleaved, and the medians
compared; CPU seconds are user + system of the command and its ranks.
Also: `diagnose` alone on the 90-s run, and 2 Monte Carlo seeds of the
90-s 1-kHz run itself (CPU seconds and peak memory, for sizing).
Prints a Markdown table and writes DIR/throughput.json. The machine's load
(`uptime`) before and after is printed too: other jobs on the cores slow
the 2-rank figures first.
"""
import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BIN = os.environ.get("TRIADCAL", os.path.join(ROOT, "build", "tools", "triadcal"))
MPIRUN = ["mpirun", "-n", "2", "--allow-run-as-root", "--oversubscribe"]


def run(cmd):
    """Wall seconds, peak resident MB (of the process itself) and CPU seconds
    (user + system, the process and the children it waited for: mpirun's
    ranks) of cmd."""
    start = time.monotonic()
    pid = os.fork()
    if pid == 0:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 1)
        os.execvp(cmd[0], cmd)
    _, status, usage = os.wait4(pid, 0)
    wall = time.monotonic() - start
    code = os.waitstatus_to_exitcode(status)
    if code != 0:
        sys.exit(f"throughput: {' '.join(cmd)} exited {code}")
    return wall, usage.ru_maxrss / 1024.0, usage.ru_utime + usage.ru_stime


def load():
    return subprocess.run(["uptime"], capture_output=True, text=True).stdout.strip()


def autogroup():
    """Linux's autogroup gives each session (this script and its mpirun ranks
    alike) one share of the CPU: on a busy machine 2 ranks then get no more
    CPU than 1, and the wall-clock speed-up says nothing about the code."""
    try:
        with open("/proc/sys/kernel/sched_autogroup_enabled") as f:
            return f.read().strip() == "1"
    except OSError:
        return False


def compare(label, cmd1, cmd2, items, repeat):
    """cmd1 on 1 rank and cmd2 on 2 ranks, interleaved `repeat` times (the
    machine's load drifts: interleaving shares the drift between both)."""
    rows = {1: [], 2: []}
    for _ in range(repeat):
        for ranks, cmd in ((1, cmd1), (2, cmd2)):
            wall, mb, cpu = run(cmd(ranks, len(rows[ranks])))
            rows[ranks].append({"wall_s": wall, "cpu_s": cpu, "peak_MB": mb})
    r = {"label": label, "items": items, "repeat": repeat}
    for ranks in (1, 2):
        walls = [x["wall_s"] for x in rows[ranks]]
        cpus = [x["cpu_s"] for x in rows[ranks]]
        r[f"ranks{ranks}"] = {"runs": rows[ranks],
                              "median_wall_s": statistics.median(walls),
                              "items_per_s": items / statistics.median(walls),
                              "cpu_s_per_item": statistics.median(cpus) / items}
    r["speedup"] = r["ranks1"]["median_wall_s"] / r["ranks2"]["median_wall_s"]
    pair = [a["wall_s"] / b["wall_s"] for a, b in zip(rows[1], rows[2])]
    r["speedup_per_repeat"] = pair
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fits", type=int, default=48)
    ap.add_argument("--seeds", type=int, default=48)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--workdir")
    a = ap.parse_args()
    work = a.workdir or tempfile.mkdtemp(prefix="triadcal_throughput_")
    os.makedirs(work, exist_ok=True)
    if not shutil.which("mpirun"):
        sys.exit("throughput: mpirun not found (Debian: openmpi-bin)")
    out = {"load_before": load(), "cores": os.cpu_count(), "autogroup": autogroup()}

    # ---- one of each alone: wall, CPU and peak memory per run
    run90 = os.path.join(work, "90s")
    run([BIN, "simulate", os.path.join(ROOT, "examples/paper-experiment3/scenario.yaml"),
         "-o", run90])
    yaml90 = os.path.join(run90, "run.yaml")
    scen = os.path.join(HERE, "scenarios", "paper-mc.yaml")
    alone = {
        "fit_90s_1kHz": [BIN, "fit", yaml90, "--threads", "1", "-o",
                         os.path.join(work, "fit.json")],
        "diagnose_90s_1kHz": [BIN, "diagnose", yaml90, "-o", os.path.join(work, "diag.json")],
        "montecarlo_1_seed_paper_mc": [BIN, "montecarlo", scen, "-n", "1", "--threads", "1",
                                       "-o", os.path.join(work, "mc_one.json")],
        "montecarlo_2_seeds_90s_1kHz": [
            BIN, "montecarlo", os.path.join(ROOT, "examples/paper-experiment3/scenario.yaml"),
            "-n", "2", "--threads", "1", "-o", os.path.join(work, "mc_1khz.json")],
    }
    out["alone"] = {}
    for name, cmd in alone.items():
        wall, mb, cpu = run(cmd)
        out["alone"][name] = {"wall_s": wall, "cpu_s": cpu, "peak_MB": mb}

    # ---- 1 rank against 2 ranks
    manifest = os.path.join(work, "manifest.csv")
    with open(manifest, "w") as f:
        f.write("serial,run\n")
        for k in range(a.fits):
            f.write(f"U{k:04d},{yaml90}\n")

    def batch(ranks, k):
        cmd = [BIN, "batch", manifest, "-o", os.path.join(work, f"b{ranks}_{k}"), "--threads", "1"]
        return cmd if ranks == 1 else MPIRUN + cmd

    def montecarlo(ranks, k):
        cmd = [BIN, "montecarlo", scen, "-n", str(a.seeds), "--threads", "1", "-o",
               os.path.join(work, f"mc{ranks}_{k}.json")]
        return cmd if ranks == 1 else MPIRUN + cmd

    out["fit"] = compare("fit, 90-s run at 1 kHz", batch, batch, a.fits, a.repeat)
    out["seed"] = compare("Monte Carlo seed, paper-mc", montecarlo, montecarlo, a.seeds,
                          a.repeat)
    out["load_after"] = load()
    with open(os.path.join(work, "throughput.json"), "w") as f:
        json.dump(out, f, indent=2)

    print(f"load before: {out['load_before']}; autogroup scheduling: {out['autogroup']}")
    print(f"load after:  {out['load_after']}")
    print()
    print("| work (median of %d, interleaved) | 1 rank | 2 ranks | speed-up (each repeat) | "
          "CPU s per item, 1 / 2 ranks |" % a.repeat)
    print("|---|---|---|---|---|")
    for key, unit in (("fit", "runs"), ("seed", "seeds")):
        r = out[key]
        each = ", ".join(f"{x:.2f}" for x in r["speedup_per_repeat"])
        print(f"| {r['label']} ({r['items']} {unit}) | {r['ranks1']['items_per_s']:.3f} {unit}/s | "
              f"{r['ranks2']['items_per_s']:.3f} {unit}/s | {r['speedup']:.2f}x ({each}) | "
              f"{r['ranks1']['cpu_s_per_item']:.3f} / {r['ranks2']['cpu_s_per_item']:.3f} |")
    print()
    print("| alone | wall s | CPU s | peak MB |")
    print("|---|---|---|---|")
    for name, x in out["alone"].items():
        print(f"| {name} | {x['wall_s']:.2f} | {x['cpu_s']:.2f} | {x['peak_MB']:.0f} |")
    print(f"wrote {os.path.join(work, 'throughput.json')}")


if __name__ == "__main__":
    main()
