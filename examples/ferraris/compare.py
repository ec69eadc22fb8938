#!/usr/bin/env python3
"""Compare a `triadcal static` OUT of the Ferraris session with the published
calibration (imucal's expected_calibration.json), element by element.

    python3 examples/ferraris/compare.py out.json [expected_calibration.json]

Their model: raw = K_a R_a a + b_a, a in m/s^2 with g = 9.81 (their value).
Ours (paper eq. 1, K_ij = 0 off the diagonal): raw = diag(K) M W + W0 + K_i K_ii,
W = a / g in g. Hence K_a R_a = diag(K) M / 9.81 [counts per m/s^2], and b_a,
the mean reading of axis i over its own two positions (+-1 g), is
W0_i + K_i K_ii.
"""
import json
import math
import os
import sys

G_FERRARIS = 9.81
ARCMIN = math.pi / (180 * 60)


def ours(out):
    p = {k: v["value"] for k, v in out["parameters"].items()}
    s = {k: v["sigma"] for k, v in out["parameters"].items()}
    K = [p["Kx"], p["Ky"], p["Kz"]]
    sK = [s["Kx"], s["Ky"], s["Kz"]]
    a = {k: p[k] * ARCMIN for k in ("alpha_x", "alpha_y", "beta_x", "beta_z", "gamma_y", "gamma_z")}
    sa = {k: s[k] * ARCMIN for k in a}
    M = [[1, -a["alpha_y"], a["beta_z"]], [a["alpha_x"], 1, -a["gamma_z"]],
         [-a["beta_x"], a["gamma_y"], 1]]
    sM = [[0, sa["alpha_y"], sa["beta_z"]], [sa["alpha_x"], 0, sa["gamma_z"]],
          [sa["beta_x"], sa["gamma_y"], 0]]
    KR = [[K[i] * M[i][j] / G_FERRARIS for j in range(3)] for i in range(3)]
    # sigma of K_i M_ij: diagonal from K, off-diagonal from the angle (K M_ij ~ K * angle)
    sKR = [[(sK[i] if i == j else K[i] * sM[i][j]) / G_FERRARIS for j in range(3)]
           for i in range(3)]
    kii = [p["Kxx"], p["Kyy"], p["Kzz"]]
    skii = [s["Kxx"], s["Kyy"], s["Kzz"]]
    W0 = [p["W0x"], p["W0y"], p["W0z"]]
    sW0 = [s["W0x"], s["W0y"], s["W0z"]]
    b = [W0[i] + K[i] * kii[i] for i in range(3)]
    return KR, sKR, b, W0, sW0, [K[i] * kii[i] for i in range(3)], [K[i] * skii[i] for i in range(3)]


def ferraris_on_our_means(out):
    """The Ferraris formulas (imucal, eqs. 19-23) applied to our still averages."""
    mean = {p["name"]: p["mean_mV"] for p in out["positions"]}
    Ud = [[(mean["xyz"[j] + "_p"][i] - mean["xyz"[j] + "_a"][i]) / (2 * G_FERRARIS)
           for j in range(3)] for i in range(3)]
    b = [(mean["xyz"[i] + "_p"][i] + mean["xyz"[i] + "_a"][i]) / 2 for i in range(3)]
    return Ud, b


def main():
    out = json.load(open(sys.argv[1]))
    here = os.path.dirname(os.path.abspath(__file__))
    default = os.path.join(here, "..", "..", "..", "shared", "data", "real",
                           "ferraris-six-position", "expected_calibration.json")
    ref = json.load(open(sys.argv[2] if len(sys.argv) > 2 else default))
    Ka, Ra, ba = ref["K_a"], ref["R_a"], ref["b_a"]
    KRref = [[Ka[i][i] * Ra[i][j] for j in range(3)] for i in range(3)]
    KR, sKR, b, W0, sW0, kk, skk = ours(out)
    F, bF = ferraris_on_our_means(out)
    print("K_a R_a [counts per m/s^2]: ours = diag(K) M / 9.81; rel = (ours - pub) / K_a,ii;")
    print("F = the Ferraris formulas on our still averages: pub - F is the choice of samples,")
    print("F - ours the estimator (weights of the two positions of a pair)")
    print(f"{'elem':6} {'published':>11} {'ours':>11} {'ours-pub':>9} {'rel':>9} {'sigma':>7}"
          f" {'pub-F':>8} {'F-ours':>8}")
    worst = 0.0
    for i in range(3):
        for j in range(3):
            d = KR[i][j] - KRref[i][j]
            worst = max(worst, abs(d) / KRref[i][i])
            print(f"({i},{j})  {KRref[i][j]:11.5f} {KR[i][j]:11.5f} {d:9.5f} "
                  f"{d / KRref[i][i]:9.2e} {sKR[i][j]:7.4f} {KRref[i][j] - F[i][j]:8.5f} "
                  f"{F[i][j] - KR[i][j]:8.5f}")
    print(f"largest |ours - pub| / K_a,ii = {worst:.2e}")
    print("b_a [counts]: ours = W0 + K_i K_ii (then W0 and K_i K_ii with their sigma)")
    print(f"{'axis':6} {'published':>11} {'ours':>11} {'ours-pub':>9} {'pub-F':>8}")
    for i in range(3):
        print(f"  {'xyz'[i]}    {ba[i]:11.5f} {b[i]:11.5f} {b[i] - ba[i]:9.5f} {ba[i] - bF[i]:8.5f}"
              f"   W0 = {W0[i]:.3f} ({sW0[i]:.3f}), K K_ii = {kk[i]:.3f} ({skk[i]:.3f})")


if __name__ == "__main__":
    main()
