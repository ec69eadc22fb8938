#!/usr/bin/env python3
"""Throughput of triadcal on this machine: fits of the paper's 90-s run and
Monte Carlo seeds, on 1 rank and on 2 MPI ranks, measured in the same run.

usage: bench/throughput.py [--fits K] [--seeds N] [--workdir DIR]
       (TRIADCAL=path/to/triadcal to use another binary)

What it runs (every rank single-threaded, so 1 rank = 1 core):
  fit    examples/paper-experiment3 (90 s at 1 kHz, 90 000 samples), once
         alone for the per-run wall time and peak memory, then K copies
         through `batch --threads 1` on 1 rank and `mpirun -n 2 batch
         --threads 1`: runs per second.
  seed   bench/scenarios/paper-mc.yaml (90 s at 100 Hz through EKF, RTS and
         batch), `montecarlo -n N --threads 1` on 1 rank and on 2 ranks:
         seeds per second, with and without the one-off CRB (rank 0).
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


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--fits", type=int, default=16)
    ap.add_argument("--seeds", type=int, default=16)
    ap.add_argument("--workdir")
    a = ap.parse_args()
    work = a.workdir or tempfile.mkdtemp(prefix="triadcal_throughput_")
    os.makedirs(work, exist_ok=True)
    if not shutil.which("mpirun"):
        sys.exit("throughput: mpirun not found (Debian: openmpi-bin)")
    out = {"load_before": load(), "cores": os.cpu_count(), "fits": a.fits, "seeds": a.seeds,
           "autogroup": autogroup()}

    # ---- fit on the paper's 90-s run
    run90 = os.path.join(work, "90s")
    run([BIN, "simulate", os.path.join(ROOT, "examples/paper-experiment3/scenario.yaml"),
         "-o", run90])
    yaml90 = os.path.join(run90, "run.yaml")
    wall, mb, cpu = run([BIN, "fit", yaml90, "--threads", "1", "-o",
                         os.path.join(work, "fit.json")])
    out["fit_single"] = {"wall_s": wall, "peak_MB": mb, "cpu_s": cpu}
    wall, mb, cpu = run([BIN, "diagnose", yaml90, "-o", os.path.join(work, "diagnose.json")])
    out["diagnose_single"] = {"wall_s": wall, "peak_MB": mb, "cpu_s": cpu}
    manifest = os.path.join(work, "manifest.csv")
    with open(manifest, "w") as f:
        f.write("serial,run\n")
        for k in range(a.fits):
            f.write(f"U{k:04d},{yaml90}\n")
    w1, mb1, c1 = run([BIN, "batch", manifest, "-o", os.path.join(work, "b1"),
                       "--threads", "1"])
    w2, _, c2 = run(MPIRUN + [BIN, "batch", manifest, "-o", os.path.join(work, "b2"),
                              "--threads", "1"])
    out["fit_batch"] = {"ranks1_wall_s": w1, "ranks1_peak_MB": mb1, "ranks2_wall_s": w2,
                        "ranks1_cpu_s": c1, "ranks2_cpu_s": c2,
                        "cpu_s_per_run_ranks1": c1 / a.fits, "cpu_s_per_run_ranks2": c2 / a.fits,
                        "ranks1_runs_per_s": a.fits / w1, "ranks2_runs_per_s": a.fits / w2,
                        "speedup": w1 / w2}

    # ---- Monte Carlo seeds
    scen = os.path.join(HERE, "scenarios", "paper-mc.yaml")
    mc = {}
    for ranks in (1, 2):
        js = os.path.join(work, f"mc{ranks}.json")
        cmd = [BIN, "montecarlo", scen, "-n", str(a.seeds), "--threads", "1", "-o", js]
        wall, mb, cpu = run(cmd if ranks == 1 else MPIRUN + cmd)
        t = json.load(open(js))["time_s"]
        mc[ranks] = {"wall_s": wall, "crb_s": t["crb"], "peak_MB": mb, "cpu_s": cpu,
                     "cpu_s_per_seed": cpu / a.seeds,
                     "seeds_per_s": a.seeds / wall,
                     "seeds_per_s_without_crb": a.seeds / (t["total"] - t["crb"])}
    wall, mb, cpu = run([BIN, "montecarlo", scen, "-n", "1", "--threads", "1", "-o",
                         os.path.join(work, "mc_one.json")])
    out["mc_one_seed"] = {"wall_s": wall, "peak_MB": mb, "cpu_s": cpu}
    # A seed of the paper's run itself (1 kHz): 10 times the samples.
    wall, mb, cpu = run([BIN, "montecarlo", os.path.join(ROOT, "examples/paper-experiment3/scenario.yaml"),
                         "-n", "2", "--threads", "1", "-o", os.path.join(work, "mc_1khz.json")])
    out["mc_1khz_two_seeds"] = {"wall_s": wall, "peak_MB": mb, "cpu_s": cpu}
    out["mc"] = {"ranks1": mc[1], "ranks2": mc[2],
                 "speedup": mc[2]["seeds_per_s"] / mc[1]["seeds_per_s"],
                 "speedup_without_crb":
                     mc[2]["seeds_per_s_without_crb"] / mc[1]["seeds_per_s_without_crb"]}
    out["load_after"] = load()
    with open(os.path.join(work, "throughput.json"), "w") as f:
        json.dump(out, f, indent=2)

    fb, m = out["fit_batch"], out["mc"]
    print(f"load before: {out['load_before']}; autogroup scheduling: {out['autogroup']}")
    print(f"load after:  {out['load_after']}")
    print()
    print("| work | 1 rank | 2 ranks | speed-up | per core, 2 ranks |")
    print("|---|---|---|---|---|")
    print(f"| fit, 90-s run at 1 kHz ({a.fits} runs) | {fb['ranks1_runs_per_s']:.3f} runs/s | "
          f"{fb['ranks2_runs_per_s']:.3f} runs/s | {fb['speedup']:.2f}x | "
          f"{fb['ranks2_runs_per_s'] / 2:.3f} runs/s |")
    print(f"| Monte Carlo seed, paper-mc ({a.seeds} seeds) | {m['ranks1']['seeds_per_s']:.3f} "
          f"seeds/s | {m['ranks2']['seeds_per_s']:.3f} seeds/s | {m['speedup']:.2f}x | "
          f"{m['ranks2']['seeds_per_s'] / 2:.3f} seeds/s |")
    print(f"| same, without the one-off CRB | {m['ranks1']['seeds_per_s_without_crb']:.3f} | "
          f"{m['ranks2']['seeds_per_s_without_crb']:.3f} | {m['speedup_without_crb']:.2f}x | |")
    print()
    print(f"one fit alone: {out['fit_single']['wall_s']:.2f} s, peak {out['fit_single']['peak_MB']:.0f} MB; "
          f"one Monte Carlo seed alone (with the CRB): {out['mc_one_seed']['wall_s']:.2f} s, "
          f"peak {out['mc_one_seed']['peak_MB']:.0f} MB; CRB {m['ranks1']['crb_s']:.2f} s")
    print(f"CPU seconds per fit: {fb['cpu_s_per_run_ranks1']:.3f} on 1 rank, "
          f"{fb['cpu_s_per_run_ranks2']:.3f} on 2 ranks; per seed: "
          f"{m['ranks1']['cpu_s_per_seed']:.3f} on 1 rank, {m['ranks2']['cpu_s_per_seed']:.3f} "
          f"on 2 ranks (launcher included)")
    d, k = out["diagnose_single"], out["mc_1khz_two_seeds"]
    print(f"diagnose alone on the 90-s run: {d['wall_s']:.2f} s wall, {d['cpu_s']:.2f} CPU s, "
          f"peak {d['peak_MB']:.0f} MB; 2 Monte Carlo seeds of the 90-s 1-kHz run: "
          f"{k['cpu_s']:.2f} CPU s, peak {k['peak_MB']:.0f} MB")
    print(f"wrote {os.path.join(work, 'throughput.json')}")


if __name__ == "__main__":
    main()
