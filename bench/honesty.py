#!/usr/bin/env python3
"""The figures of the honesty issue (#11), measured: is sigma honest on short,
slow, mis-declared, unconstrained, weakly excited and real runs?

usage: bench/honesty.py [--only a,b] [--seeds N] [--diagnose-seeds N]
                        [--bias-seeds N] [--workdir DIR]

Sections (all by default):
  short     paper profile, 2 mV: a 20-s run at 50 Hz and a 90-s run at 20 Hz,
            `montecarlo --estimators batch` over N seeds (20): parameters held in
            some run although their CRB is finite, sigma / CRB per parameter, RMS
            of (estimate - truth) / sigma per group.
  noise     50 Hz, 90 s, true noise 2 mV, declared 0.2 mV (10x too small) and
            6 mV (3x too large): mean sigma / CRB of the TRUE noise (the CRB from
            the correctly declared Monte Carlo), and the warning of one fit.
  diagnose_noise  the same run, declared 0.5 mV (4x too small) and 6 mV (3x
            too large), N seeds (10) through `diagnose`: mean sigma / CRB of the
            true noise per parameter after the loop (its smallest), the largest
            |error| / sigma, and how often an effect was selected (none is in
            the data).
  unconstrained  the paper run without its pseudo-measurement: are gamma_y,
            gamma_z, dlambda2 reported estimable on their own, is the direction in
            "unobservable"?
  diagnose  N clean seeds (100) of the 50-Hz run through `diagnose`: share with
            "structure" (its stated alpha: 1e-3 per whitened channel, 6
            channels) with each alarm's summary, the share of the channels'
            Ljung-Box p-values below 0.1 .. 0.001 (uniform under the model),
            mean lag-1 autocorrelation of the whitened process
            residuals per channel, as tested (excess over what the fit itself
            leaves) and raw.
  bias      scale-factor bias: mean (estimate - truth) / CRB of Kx, Ky, Kz over
            N seeds (400) of bench/scenarios/paper-mc.yaml at 2 mV and at 6 mV
            (standard error of each mean: 1/sqrt(N)).
  vertical  bench/scenarios/vertical-shaft.yaml, 5 seeds: converged,
            (K - nominal) / sigma, sigma / prior sigma, what the output names.
  coloured  bench/scenarios/paper-coloured.yaml (reading noise correlated in
            time, 0.5 s), 90 s and 360 s, N seeds (20) each through `fit`: RMS (estimate - truth) /
            sigma per group with the reported sigma, the model's white sigma
            and the HAC sigma; which one was reported; the bandwidth.
  unalike   bench/scenarios/paper-unalike.yaml (white reading noise 2 / 10 / 2
            mV, noise_mV: auto: one weight serves the three channels), N seeds
            (20) through `fit`: RMS z per channel's parameters with the
            reported, white and HAC sigma, and sigma / that of the fit weighted
            with the true per-channel noise.
  real      the real roll runs (needs the shared data folder; skipped without
            it): each run fitted whole and in halves (time_range_s) with the
            noise estimated (noise_mV: auto) and the loop's effects
            (--real-effects, angle_latency,thermal_drift), nothing held by hand
            (--real-hold, '': what the fit holds or considers it decides
            itself); the halves' estimates compared, chi2 = (a - b)^2 /
            (sigma_a^2 + sigma_b^2) per parameter determined by both, with the
            sigma given the considered values (common to both halves) plus
            what those leave in the difference, median over parameters, with
            the 5-95 % band of that median for honest sigma given the
            parameters' correlations (drawn from the halves' correlation given
            the considered values, `fit --correlations`; needs numpy); then
            the three speeds compared with the reported sigma.
"""
import argparse
import json
import math
import os
import re
import statistics
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BIN = os.environ.get("TRIADCAL", os.path.join(ROOT, "build", "tools", "triadcal"))
BASE = os.path.join(HERE, "scenarios", "paper-mc.yaml")
GROUPS = {
    "scale": ["Kx", "Ky", "Kz"],
    "zero offset": ["W0x", "W0y", "W0z"],
    "non-orthogonality": ["alpha_x", "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z"],
    "K_ij": ["Kxx", "Kxy", "Kxz", "Kyx", "Kyy", "Kyz", "Kzx", "Kzy", "Kzz"],
    "bench": ["dpsi", "dtheta_c", "dlambda2"],
    "lever arm": ["dx2", "dy2", "dz2"],
}


def run(cmd, check=True):
    p = subprocess.run(cmd, capture_output=True, text=True)
    if check and p.returncode != 0:
        sys.exit(f"honesty: {' '.join(cmd)} exited {p.returncode}: {p.stderr.strip()[-400:]}")
    return p


def scenario(work, name, rate_hz=50, duration_s=90, noise_mV=2.0, declared=None,
             constraints=True, base=BASE):
    s = open(base).read()
    s = re.sub(r"rate_hz: \d+.*", f"rate_hz: {rate_hz}", s)
    s = re.sub(r"duration_s: \d+.*", f"duration_s: {duration_s}", s)
    s = re.sub(r"accel_mV: [0-9.]+", f"accel_mV: {noise_mV}", s)
    if declared is not None:
        s = s.replace("    # noise_mV: taken from noise.accel_mV", f"    noise_mV: {declared}")
    if not constraints:
        s = re.sub(r"  constraints:\n(    #.*\n)*    - \{expr.*\n", "  constraints: []\n", s)
        s = s.replace("truth_spread:\n  dlambda2: 0.5   # arcmin = 30\"\n", "")
    path = os.path.join(work, name + ".yaml")
    open(path, "w").write(s)
    return path


def montecarlo(work, scen, seeds, name):
    out = os.path.join(work, name + ".json")
    run([BIN, "montecarlo", scen, "-n", str(seeds), "--estimators", "batch", "-o", out, "-q",
         "--force"])
    return json.load(open(out))


def short(work, a):
    print("\n## short and slow runs (2 mV)\n")
    for label, rate, dur in (("20-s run at 50 Hz", 50, 20), ("90-s run at 20 Hz", 20, 90)):
        m = montecarlo(work, scenario(work, f"short{rate}_{dur}", rate, dur), a.seeds, f"mc{rate}_{dur}")
        held = [n for n, p in m["parameters"].items()
                if p["batch"]["held_runs"] > 0 and math.isfinite(p["crb"]) and p["crb"] > 0]
        ratios = {n: p["batch"]["mean_sigma"] / p["crb"] for n, p in m["parameters"].items()
                  if p["crb"] > 0 and p["batch"]["held_runs"] == 0}
        lo = min(ratios, key=ratios.get)
        hi = max(ratios, key=ratios.get)
        print(f"{label}, {a.seeds} seeds: held with a finite CRB: {held or 'none'}; "
              f"sigma/CRB {ratios[lo]:.3f} ({lo}) .. {ratios[hi]:.3f} ({hi})")
        for g, names in GROUPS.items():
            z2 = [m["parameters"][n]["batch"]["rms_normalised_error"] ** 2 for n in names
                  if m["parameters"][n]["batch"]["held_runs"] == 0]
            if z2:
                print(f"  RMS z {g:18s} {math.sqrt(sum(z2) / len(z2)):.3f}")


def noise(work, a):
    print("\n## declared noise wrong (true 2 mV, 50 Hz, 90 s)\n")
    ref = montecarlo(work, scenario(work, "noise_ref"), a.seeds, "noise_ref")
    crb = {n: p["crb"] for n, p in ref["parameters"].items()}
    for declared in (0.2, 6.0):
        scen = scenario(work, f"noise_{declared}", declared=declared)
        m = montecarlo(work, scen, a.seeds, f"noise_{declared}")
        r = {n: p["batch"]["mean_sigma"] / crb[n] for n, p in m["parameters"].items()
             if crb[n] > 0 and p["batch"]["held_runs"] == 0}
        lo, hi = min(r, key=r.get), max(r, key=r.get)
        rms = math.sqrt(statistics.mean(p["batch"]["rms_normalised_error"] ** 2
                                        for p in m["parameters"].values()
                                        if p["batch"]["held_runs"] == 0))
        d = os.path.join(work, f"noise_run_{declared}")
        run([BIN, "simulate", scen, "-o", d, "-q", "--seed", "1", "--force"])
        p = run([BIN, "fit", os.path.join(d, "run.yaml"), "-o", os.path.join(d, "fit.json"),
                 "-q", "--force"])
        warning = next((l for l in p.stderr.splitlines() if "noise_mV" in l), "(no warning)")
        print(f"declared {declared} mV, {a.seeds} seeds: sigma / CRB(true noise) "
              f"{r[lo]:.3f} ({lo}) .. {r[hi]:.3f} ({hi}); pooled RMS z {rms:.3f}")
        print(f"  {warning.strip()}")


def diagnose_noise(work, a):
    print("\n## diagnose with the declared noise wrong (true 2 mV, 50 Hz, 90 s)\n")
    ref = montecarlo(work, scenario(work, "noise_ref"), a.seeds, "noise_ref")
    crb = {n: p["crb"] for n, p in ref["parameters"].items()}
    for declared in (0.5, 6.0):
        scen = scenario(work, f"dnoise_{declared}", declared=declared)
        ratios, worst, selected = {}, (0.0, "", 0), 0
        for seed in range(1, a.diagnose_noise_seeds + 1):
            d = os.path.join(work, f"dnoise_{declared}_{seed}")
            run([BIN, "simulate", scen, "-o", d, "-q", "--seed", str(seed), "--force"])
            out = os.path.join(d, "diagnose.json")
            p = run([BIN, "diagnose", os.path.join(d, "run.yaml"), "-o", out, "-q", "--force"],
                    check=False)
            if p.returncode not in (0, 4):
                sys.exit(f"honesty: diagnose of seed {seed} exited {p.returncode}: "
                         f"{p.stderr.strip()[-300:]}")
            j = json.load(open(out))
            truth = json.load(open(os.path.join(d, "truth.json")))["parameters"]
            selected += 1 if j["selected"] else 0
            for n, q in j["parameters"].items():
                if not q.get("estimable") or not q.get("sigma"):
                    continue
                if crb.get(n, 0) > 0:
                    ratios.setdefault(n, []).append(q["sigma"] / crb[n])
                if n in truth:
                    z = abs(q["value"] - truth[n]) / q["sigma"]
                    if z > worst[0]:
                        worst = (z, n, seed)
        mean = {n: statistics.mean(v) for n, v in ratios.items()}
        lo = min(mean, key=mean.get)
        print(f"declared {declared} mV (true 2), {a.diagnose_noise_seeds} seeds through "
              f"diagnose: mean sigma / CRB(true noise) >= {mean[lo]:.3f} ({lo}), largest "
              f"{max(mean.values()):.3f}; largest |error| / sigma {worst[0]:.2f} ({worst[1]}, "
              f"seed {worst[2]}); an effect selected on {selected} seeds (none injected)")


def unconstrained(work, a):
    print("\n## without the pseudo-measurement dpsi - dlambda2\n")
    scen = scenario(work, "uncon", constraints=False)
    d = os.path.join(work, "uncon_run")
    run([BIN, "simulate", scen, "-o", d, "-q", "--seed", "1", "--force"])
    run([BIN, "fit", os.path.join(d, "run.yaml"), "-o", os.path.join(d, "fit.json"), "-q",
         "--force"])
    f = json.load(open(os.path.join(d, "fit.json")))
    for n in ("gamma_y", "gamma_z", "dlambda2"):
        p = f["parameters"][n]
        print(f"{n:9s} estimable {p['estimable']}, sigma {p['sigma']}, "
              f"relative_to {p.get('relative_to', '-')}")
    dirs = [d["description"] for d in f["unobservable"]]
    print(f"unobservable: {dirs}")


def diagnose(work, a):
    print(f"\n## diagnose on {a.diagnose_seeds} clean seeds (50 Hz, 90 s, 2 mV)\n")
    scen = scenario(work, "clean50")
    excess, raw = {}, {}
    structure = 0
    selected = 0
    alarms = []
    pvalues = []
    procs = []

    def finish(seed, d, p):
        nonlocal structure, selected
        if p.wait() != 0:
            sys.exit(f"honesty: diagnose of seed {seed} failed")
        j = json.load(open(os.path.join(d, "d.json")))
        r = j["after"]["residual"]
        structure += bool(r["structure"])
        if r["structure"]:
            alarms.append(f"seed {seed}: {r['structure_summary']}")
        selected += bool(j["selected"])
        for c in r["channels"]:
            if c.get("in_whiteness_test"):
                pvalues.append(c["ljung_box_p"])
                excess.setdefault(c["channel"], []).append(c["lag1_autocorrelation"])
                raw.setdefault(c["channel"], []).append(
                    c["lag1_autocorrelation"] + c.get("lag1_expected_under_model", 0.0))

    for seed in range(1, a.diagnose_seeds + 1):
        d = os.path.join(work, f"clean_{seed}")
        run([BIN, "simulate", scen, "-o", d, "-q", "--seed", str(seed), "--force"])
        procs.append((seed, d, subprocess.Popen(
            [BIN, "diagnose", os.path.join(d, "run.yaml"), "-o", os.path.join(d, "d.json"), "-q",
             "--force"], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)))
        if len(procs) >= 2:
            finish(*procs.pop(0))
    for p in procs:
        finish(*p)
    n = a.diagnose_seeds
    print(f"structure reported: {structure} of {n} ({100.0 * structure / n:.1f} %; stated alpha "
          f"1e-3 per channel, 6 channels: 0.6 %); an effect selected: {selected} of {n}")
    for line in alarms:
        print(f"  {line}")
    # Under the model the channels' Ljung-Box p-values are uniform.
    print(f"Ljung-Box p-values of the {len(pvalues)} tested channels: share below " + ", ".join(
        f"{lvl:g}: {sum(p < lvl for p in pvalues) / len(pvalues):.4f}"
        for lvl in (0.1, 0.05, 0.01, 0.001)))
    se = 1.0 / math.sqrt(n * 180)
    print(f"mean lag-1 autocorrelation per whitened channel (standard error ~{se:.3f}):")
    for ch in excess:
        print(f"  {ch:22s} tested (excess) {statistics.mean(excess[ch]):+.3f}   "
              f"raw {statistics.mean(raw[ch]):+.3f}")


def bias(work, a):
    print(f"\n## scale-factor bias, {a.bias_seeds} seeds of paper-mc (100 Hz, 90 s)\n")
    for mv in (2.0, 6.0):
        m = montecarlo(work, scenario(work, f"bias{mv}", rate_hz=100, noise_mV=mv),
                       a.bias_seeds, f"bias{mv}")
        row = ", ".join(f"{k} {m['parameters'][k]['batch']['bias_over_crb']:+.3f}"
                        for k in ("Kx", "Ky", "Kz"))
        worst = max(m["parameters"].items(), key=lambda kv: abs(kv[1]["batch"]["bias_over_crb"]))
        print(f"{mv} mV: mean z {row} (standard error {1 / math.sqrt(a.bias_seeds):.3f}); "
              f"largest of all: {worst[0]} {worst[1]['batch']['bias_over_crb']:+.3f}")


def vertical(work, a):
    print("\n## vertical shaft (bench/scenarios/vertical-shaft.yaml)\n")
    scen = os.path.join(HERE, "scenarios", "vertical-shaft.yaml")
    for seed in range(1, 6):
        d = os.path.join(work, f"vs_{seed}")
        run([BIN, "simulate", scen, "-o", d, "-q", "--seed", str(seed), "--force"])
        run([BIN, "fit", os.path.join(d, "run.yaml"), "-o", os.path.join(d, "fit.json"), "-q",
             "--force"], check=False)
        f = json.load(open(os.path.join(d, "fit.json")))
        ks = []
        for k in ("Kx", "Ky", "Kz"):
            p = f["parameters"][k]
            if p.get("sigma") is None or not p.get("determined", True):
                ks.append(f"{k} {p['value']:.1f} (not determined: "
                          f"{'considered' if p.get('considered') else 'held'} at nominal)")
            else:
                ks.append(f"{k} {(p['value'] - 174.0) / p['sigma']:+.2f} sigma "
                          f"(sigma {p['sigma']:.1f})")
        print(f"seed {seed}: converged {f['converged']}, chi2/dof {f['chi2_per_dof']:.3f}; "
              f"from nominal: {', '.join(ks)}; not estimable: "
              f"{[n for n in f['not_estimable'] if n[0] in 'KW' and len(n) <= 3]}")


def z_table(work, a, scen, tag, groups, efficient_noise=None):
    """RMS (estimate - truth) / sigma per group over a.seeds seeds of scen
    through `fit`, with the reported sigma, the model's white one and the HAC
    one. efficient_noise: a noise_mV line for run.yaml with which the same data
    are also fitted (the truly weighted fit), to give sigma / its sigma."""
    z = {m: {g: [] for g in groups} for m in ("sigma", "sigma_white", "sigma_hac")}
    ratio = {g: [] for g in groups}
    methods, bands, floors = [], [], []
    for seed in range(1, a.seeds + 1):
        d = os.path.join(work, f"{tag}_{seed}")
        run([BIN, "simulate", scen, "-o", d, "-q", "--seed", str(seed), "--force"])
        run([BIN, "fit", os.path.join(d, "run.yaml"), "-o", os.path.join(d, "fit.json"),
             "-q", "--force"])
        f = json.load(open(os.path.join(d, "fit.json")))
        t = json.load(open(os.path.join(d, "truth.json")))["parameters"]
        eff = None
        if efficient_noise:
            y = os.path.join(d, "run_efficient.yaml")
            open(y, "w").write(re.sub(r"noise_mV: .*", efficient_noise,
                                      open(os.path.join(d, "run.yaml")).read()))
            run([BIN, "fit", y, "-o", os.path.join(d, "fit_efficient.json"), "-q", "--force"])
            eff = json.load(open(os.path.join(d, "fit_efficient.json")))["parameters"]
        methods.append(f["sigma_method"])
        bands.append(f["hac"]["bandwidth_epochs"])
        floors.append(f["hac"].get("floor", "-"))
        for g, names in groups.items():
            for n in names:
                p = f["parameters"][n]
                if p["sigma"] is None or not p["estimable"]:
                    continue
                tv = t[n]["value"] if isinstance(t[n], dict) else t[n]
                for m in z:
                    z[m][g].append((p["value"] - tv) / p[m])
                if eff and eff[n]["sigma"]:
                    ratio[g].append(p["sigma"] / eff[n]["sigma"])
    print(f"{a.seeds} seeds: sigma reported from {methods.count('hac')} HAC / "
          f"{methods.count('white')} white fits (HAC floor: "
          + ", ".join(f"{k} {floors.count(k)}" for k in sorted(set(floors)))
          + f"); bandwidth {min(bands):.1f}-{max(bands):.1f} epochs")
    head = f"  {'RMS z':18s} {'reported':>9s} {'white':>9s} {'HAC':>9s}"
    if efficient_noise:
        head += "   mean sigma / sigma of the truly weighted fit"
    print(head)
    for g in groups:
        cells = [math.sqrt(statistics.mean(v * v for v in z[m][g])) if z[m][g]
                 else float("nan") for m in z]
        line = f"  {g:18s} " + " ".join(f"{c:9.3f}" for c in cells)
        if efficient_noise and ratio[g]:
            line += f"   {statistics.mean(ratio[g]):.2f}"
        print(line)
    allz = [math.sqrt(statistics.mean(v * v for g in groups for v in z[m][g])) for m in z]
    print(f"  {'all':18s} " + " ".join(f"{c:9.3f}" for c in allz))


def coloured(work, a):
    print("\n## reading noise correlated in time (bench/scenarios/paper-coloured.yaml)\n")
    base = open(os.path.join(HERE, "scenarios", "paper-coloured.yaml")).read()
    for duration in (90, 360):
        scen = os.path.join(work, f"coloured_{duration}.yaml")
        open(scen, "w").write(re.sub(r"duration_s: \d+.*", f"duration_s: {duration}", base))
        print(f"{duration}-s runs:")
        z_table(work, a, scen, f"col_{duration}", GROUPS)


# Parameters by the channel they belong to (bench/scenarios/paper-unalike.yaml
# makes y's noise 5x x's and z's).
CHANNEL_GROUPS = {
    "x channel (2 mV)": ["Kx", "W0x", "Kxx", "Kxy", "Kxz"],
    "y channel (10 mV)": ["Ky", "W0y", "Kyx", "Kyy", "Kyz"],
    "z channel (2 mV)": ["Kz", "W0z", "Kzx", "Kzy", "Kzz"],
    "angles": ["alpha_x", "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z"],
    "bench": ["dpsi", "dtheta_c", "dlambda2"],
    "lever arm": ["dx2", "dy2", "dz2"],
}


def unalike(work, a):
    print("\n## channels whose noise differs 5x (bench/scenarios/paper-unalike.yaml, "
          "2 / 10 / 2 mV, noise_mV: auto)\n")
    z_table(work, a, os.path.join(HERE, "scenarios", "paper-unalike.yaml"), "unalike",
            CHANNEL_GROUPS, efficient_noise="noise_mV: [2, 10, 2]")


def shared_folder():
    for c in (os.environ.get("TRIADCAL_SHARED", ""), os.path.join(ROOT, "..", "shared")):
        if c and os.path.isdir(os.path.join(c, "data", "real", "single-axis-encoder")):
            return c
    return None


def median_band(fa, fb, var_diff, observed, draws=20000, seed=1):
    """The median over parameters of (a - b)^2 / var(a - b) when sigma is
    honest is 0.455 for independent parameters; correlated ones widen its
    spread. Draws the halves' difference with its correlation (the halves are
    independent data: the covariance of a - b is that of a plus that of b,
    each given the considered values, with var_diff, the per-parameter variance the halves are judged on)
    and returns the 5 %, 50 %, 95 % points of the median and the chance of
    one at least as far from 0.455 on the observed side. None without
    correlations in the fits (--correlations) or numpy."""
    try:
        import numpy as np
    except ImportError:
        return None
    names = list(var_diff)
    def block(f):
        c = f.get("correlation_given_consider") or f.get("correlation")
        if not c:
            return None
        idx = {n: i for i, n in enumerate(c["names"])}
        m = np.array(c["matrix"])
        k = [idx[n] for n in names]
        return m[np.ix_(k, k)]
    ra, rb = block(fa), block(fb)
    if ra is None or rb is None:
        return None
    pa, pb = fa["parameters"], fb["parameters"]
    sa = np.array([pa[n].get("sigma_given_consider", pa[n]["sigma"]) for n in names])
    sb = np.array([pb[n].get("sigma_given_consider", pb[n]["sigma"]) for n in names])
    cov = np.outer(sa, sa) * ra + np.outer(sb, sb) * rb
    # var_diff includes what the considered values leave (consider term):
    # added on the diagonal, uncorrelated (a conservative spread).
    var = np.array([var_diff[n] for n in names])
    cov += np.diag(np.maximum(var - np.diag(cov), 0.0))
    d = np.sqrt(np.diag(cov))
    r = cov / np.outer(d, d)
    w, v = np.linalg.eigh(r)
    root = v * np.sqrt(np.maximum(w, 0.0))
    z = np.random.default_rng(seed).standard_normal((draws, len(names))) @ root.T
    med = np.median(z * z, axis=1)
    lo, mid, hi = np.percentile(med, [5, 50, 95])
    p = float(np.mean(med >= observed)) if observed >= mid else float(np.mean(med <= observed))
    return lo, mid, hi, p


# The median of a chi-square with 1 degree of freedom: what the median of
# (a - b)^2 / (sigma_a^2 + sigma_b^2) over parameters is when sigma is honest
# (its mean is 1).
CHI2_1_MEDIAN = 0.455


def real(work, a):
    print("\n## real roll runs: halves and speeds, noise estimated\n")
    if not shared_folder():
        print("skipped: the shared data folder is not here (set TRIADCAL_SHARED)")
        return
    ex = os.path.join(ROOT, "examples", "single-axis-roll")
    whole = {}
    for speed in a.real_runs.split(","):
        text = open(os.path.join(ex, speed + ".yaml")).read()
        text = re.sub(r"noise_mV: \d+", "noise_mV: auto", text)
        fits = []
        for label, rng in (("whole", None), ("first half", 0), ("second half", 1)):
            t = text
            if rng is not None:
                span = whole[speed]["span"]
                mid = 0.5 * (span[0] + span[1])
                lo, hi = (span[0], mid) if rng == 0 else (mid, span[1])
                t += f"\ntime_range_s: [{lo}, {hi}]\n"
            y = os.path.join(ex, f".honesty_{speed}_{label.replace(' ', '_')}.yaml")
            open(y, "w").write(t)
            out = os.path.join(work, f"real_{speed}_{label.replace(' ', '_')}.json")
            cmd = [BIN, "fit", y, "-o", out, "-q", "--force", "--correlations", "--residuals",
                   out.replace(".json", ".csv")]
            if a.real_effects:
                cmd += ["--effects", a.real_effects]
            if a.real_hold:
                cmd += ["--hold", a.real_hold]
            try:
                p = subprocess.run(cmd, capture_output=True, text=True, timeout=a.real_timeout)
                if p.returncode not in (0, 4):  # 4: written, but not converged
                    sys.exit(f"honesty: fit of {speed} {label} exited {p.returncode}: "
                             f"{p.stderr.strip()[-300:]}")
            except subprocess.TimeoutExpired:
                print(f"{speed} {label}: fit stopped after {a.real_timeout} s")
                fits = None
                break
            finally:
                os.remove(y)
            f = json.load(open(out))
            if rng is None:
                ts = [float(l.split(",")[0]) for l in open(out.replace(".json", ".csv"))
                      if l[0].isdigit()]
                f["span"] = (ts[0], ts[-1])
                whole[speed] = f
            fits.append(f)
        if fits is None:
            continue
        a_, b_ = fits[1]["parameters"], fits[2]["parameters"]
        # Both halves consider (nearly) the same parameters at the same
        # nominal values: that part of their error is common and cancels in
        # the difference, so the halves are compared with the sigma given the
        # considered values (sigma_given_consider; the reported sigma include it).
        def chi_of(key):
            def sg(p):
                return p.get(key, p["sigma"]) if key else p["sigma"]
            return {n: (a_[n]["value"] - b_[n]["value"]) ** 2 / (sg(a_[n]) ** 2 + sg(b_[n]) ** 2)
                    for n in a_ if a_[n].get("determined") and b_[n].get("determined") and a_[n]["sigma"]
                    and b_[n]["sigma"]}
        # What the considered parameters leave in the difference: each half's
        # estimate follows the considered values' common error delta (their
        # nominal values, the same in both halves) by its own sensitivity
        # S_h, so a - b carries (S_a - S_b) delta, delta ~ diag(prior
        # sigma^2); a parameter considered in one half alone adds S P S^T
        # of that half.
        def consider_var(name):
            pa = {p["parameter"]: p for p in fits[1].get("consider", [])}
            pb = {p["parameter"]: p for p in fits[2].get("consider", [])}
            v = 0.0
            for q in set(pa) | set(pb):
                sa = pa[q].get("sensitivity", {}).get(name, 0.0) if q in pa else 0.0
                sb = pb[q].get("sensitivity", {}).get(name, 0.0) if q in pb else 0.0
                prior = (pa.get(q) or pb.get(q))["prior_sigma"]
                v += (sa - sb) ** 2 * prior ** 2
            return v
        var_diff = {n: a_[n].get("sigma_given_consider", a_[n]["sigma"]) ** 2 +
                       b_[n].get("sigma_given_consider", b_[n]["sigma"]) ** 2 + consider_var(n)
                    for n in a_ if a_[n].get("determined") and b_[n].get("determined") and a_[n]["sigma"]
                    and b_[n]["sigma"]}
        chi = {n: (a_[n]["value"] - b_[n]["value"]) ** 2 / v for n, v in var_diff.items()}
        band = median_band(fits[1], fits[2], var_diff, statistics.median(chi.values()))
        chi_given = chi_of("sigma_given_consider")
        chi_reported = chi_of(None)
        pins = [[p["parameter"] for p in f.get("consider", [])] for f in fits]
        worst = sorted(chi.items(), key=lambda kv: -kv[1])[:3]
        conv = ", ".join(f"{l} {'converged' if f['converged'] else 'NOT converged'}"
                         for l, f in zip(("whole", "first half", "second half"), fits))
        print(f"{speed}: {conv}; sigma {', '.join(f['sigma_method'] for f in fits)}")
        if a.real_effects:
            for l, f in zip(("whole", "first half", "second half"), fits):
                tau = f["parameters"].get("angle_latency.tau")
                if tau:
                    print(f"  {l}: angle_latency.tau {tau['value']:.3f} +- {tau['sigma']:.3f} "
                          f"{tau['unit']}; Kx Ky Kz " + " ".join(
                              f"{f['parameters'][k]['value']:.1f}" for k in ("Kx", "Ky", "Kz")))
        print(f"{speed}: noise estimated {[round(x, 1) for x in whole[speed]['noise']['used_mV']]} mV; "
              f"halves agree at median chi2/dof {statistics.median(chi.values()):.2f} "
              f"(x {statistics.median(chi.values()) / CHI2_1_MEDIAN:.2f} the median of chi2 with "
              f"1 dof, {CHI2_1_MEDIAN}, that honest sigma give) over "
              f"{len(chi)} parameters (largest: "
              + ", ".join(f"{n} {c:.1f}" for n, c in worst) + f"); mean {statistics.mean(chi.values()):.2f}, "
              f"without the largest {statistics.mean(sorted(chi.values())[:-1]):.2f} (1 when honest)")
        if band is None:
            print(f"{speed}: the band of the median that honest sigma give is not drawn: "
                  f"this python ({sys.executable}) has no numpy, or a fit wrote no "
                  f"correlations (Debian: python3-numpy, with /usr/bin/python3)")
        else:
            lo, mid, hi, p = band
            print(f"{speed}: honest sigma, given the {len(chi)} parameters' correlations, give a "
                  f"median of {mid:.2f} (5-95 %: {lo:.2f}-{hi:.2f}); one as far out as "
                  f"{statistics.median(chi.values()):.2f}: p {p:.3g}")
        if any(pins):
            print(f"{speed}: considered (whole, halves) {pins}; the difference judged with "
                  f"the sigma given the considered values plus what they leave in it ((S_a - "
                  f"S_b) P (S_a - S_b)); with the sigma given them alone: median chi2/dof "
                  f"{statistics.median(chi_given.values()):.2f}; with the reported sigma, which "
                  f"include their whole uncertainty twice: "
                  f"{statistics.median(chi_reported.values()):.2f}")
    if len(whole) < 3:
        return
    names = [n for n in whole["slow"]["parameters"]
             if all(whole[s]["parameters"][n].get("determined") and whole[s]["parameters"][n]["sigma"]
                    for s in whole)]
    rows = []
    for n in names:
        ps = [whole[s]["parameters"][n] for s in ("slow", "medium", "fast")]
        w = [1 / p["sigma"] ** 2 for p in ps]
        mean = sum(wi * p["value"] for wi, p in zip(w, ps)) / sum(w)
        rows.append((sum(((p["value"] - mean) / p["sigma"]) ** 2 for p in ps) / 2, n, ps))
    rows.sort(reverse=True)
    print(f"three speeds (whole runs): median chi2/dof {statistics.median(r[0] for r in rows):.2f} "
          f"over {len(rows)} parameters; beyond their sigma (chi2/dof > 4):")
    for c, n, ps in rows:
        if c > 4:
            print(f"  {n:9s} chi2/dof {c:8.1f}: " + ", ".join(
                f"{p['value']:.5g} +- {p['sigma']:.2g}" for p in ps) + f" {ps[0]['unit']}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--only",
                    default="short,noise,diagnose_noise,unconstrained,diagnose,bias,vertical,"
                            "coloured,unalike,real")
    ap.add_argument("--seeds", type=int, default=20)
    ap.add_argument("--diagnose-seeds", type=int, default=100)
    ap.add_argument("--bias-seeds", type=int, default=400)
    ap.add_argument("--diagnose-noise-seeds", type=int, default=10)
    ap.add_argument("--workdir", default="")
    ap.add_argument("--real-effects", default="angle_latency,thermal_drift",
                    help="effects fitted on the real runs (what the loop finds there; '' none)")
    ap.add_argument("--real-hold", default="",
                    help="parameters held on the real runs by hand ('' none, the default: "
                         "the fit decides before it starts what the run does not determine, "
                         "docs/method.md)")
    ap.add_argument("--real-runs", default="slow,medium,fast",
                    help="which real roll runs (slow,medium,fast)")
    ap.add_argument("--real-timeout", type=float, default=1200.0,
                    help="seconds one real fit may take before that speed is skipped")
    a = ap.parse_args()
    work = a.workdir or tempfile.mkdtemp(prefix="triadcal_honesty_")
    os.makedirs(work, exist_ok=True)
    sections = {"short": short, "noise": noise, "diagnose_noise": diagnose_noise,
                "unconstrained": unconstrained,
                "diagnose": diagnose, "bias": bias, "vertical": vertical, "coloured": coloured,
                "unalike": unalike, "real": real}
    for name in a.only.split(","):
        if name not in sections:
            sys.exit(f"honesty: --only: unknown section '{name}' ({', '.join(sections)})")
        sections[name](work, a)
        sys.stdout.flush()
    print(f"\n(work files in {work})")


if __name__ == "__main__":
    main()
