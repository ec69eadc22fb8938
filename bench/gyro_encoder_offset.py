#!/usr/bin/env python3
"""Where the shaft gyro's increment residual of a real single-axis run comes from.

Usage:
  triadcal fit examples/single-axis-roll/slow_gyro.yaml -o fit.json
  triadcal apply fit.json examples/single-axis-roll/slow_gyro.yaml -o applied.csv
  python3 bench/gyro_encoder_offset.py applied.csv [AXIS]     (AXIS: omega_y, the shaft)

Compares, over 10-sample intervals, the calibrated gyro's angle increment
(trapezoid over the logged time stamps) with the encoder's (lambda1), and
prints the residual RMS [arcsec] under each explanation: the logged stamps
against a uniform time axis (time-stamp jitter), a scale error (regression),
the gyro shifted against the encoder by whole samples, and the encoder
corrected by tau x its rate (what a latency taken to first order does).
"""
import sys

import numpy as np


def main():
    path = sys.argv[1]
    axis = sys.argv[2] if len(sys.argv) > 2 else "omega_y"
    with open(path) as f:
        lines = [line for line in f if not line.startswith("#")]
    d = np.genfromtxt(lines, delimiter=",", names=True)
    t, w, lam = d["t"], d[axis], d["lambda1"]
    n = len(t)
    k = np.arange(5, n - 20, 10)

    def gyro_increments(tt):
        c = np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(tt))])
        return c[k + 10] - c[k]

    def rms(r):
        return 3600.0 * np.sqrt(np.mean(r ** 2))

    dt = np.diff(t)
    print(f"{n} samples, dt median {np.median(dt) * 1e3:.2f} ms, sd {dt.std() * 1e3:.2f} ms, "
          f"{(dt > 0.015).sum()} gaps > 15 ms")
    g = gyro_increments(t)
    e = lam[k + 10] - lam[k]
    print(f"residual as logged:                   {rms(g - e):6.0f} arcsec")
    uniform = t[0] + np.arange(n) * dt.mean()
    print(f"uniform time axis (no stamp jitter):  {rms(gyro_increments(uniform) - e):6.0f} arcsec")
    a = np.vstack([e, np.full_like(e, 0.1)]).T
    coef, *_ = np.linalg.lstsq(a, g, rcond=None)
    print(f"scale and bias refitted ({coef[0]:.4f}, {coef[1]:.4f} deg/s): "
          f"{rms(g - a @ coef):6.0f} arcsec")
    for s in (-1, 1, 2):
        es = lam[k + 10 - s] - lam[k - s]
        print(f"gyro {s * 10:+d} ms late on the encoder:     {rms(g - es):6.0f} arcsec")
    rate = np.gradient(lam, t)
    for tau in (0.005, 0.0085, 0.010):
        lc = lam - tau * rate
        print(f"encoder - {tau * 1e3:.1f} ms x its rate:      "
              f"{rms(g - (lc[k + 10] - lc[k])):6.0f} arcsec")


if __name__ == "__main__":
    main()
