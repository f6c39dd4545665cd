#!/usr/bin/env python3
"""Frequency-response speed, SciPy beside helicon-ident, on one 100 s, 400 Hz log.

The log is the one of crates/ident/benches/frf.rs (same formula): x a
logarithmic sweep 0.05 -> 5 Hz plus a deterministic disturbance, y = x through
a first-order lag plus another disturbance. SciPy computes the single-window
estimate (csd + two welch, 10 s Hann windows, half overlap, then H and the
coherence); then this script runs `cargo bench -p helicon-ident --bench frf`
and prints both medians.

Usage (repository root): python3 tools/bench_ident_scipy.py [--no-rust]
"""
import os
import re
import statistics
import subprocess
import sys
import timeit

import numpy as np
import scipy
from scipy import signal


def log_100s_400hz():
    n, dt = 40_000, 1.0 / 400.0
    f0, f1, t1 = 0.05, 5.0, 100.0
    k = np.log(f1 / f0) / t1
    i = np.arange(n, dtype=float)
    t = i * dt
    x = np.sin(2 * np.pi * f0 * (np.exp(k * t) - 1.0) / k) + 0.1 * (np.fmod(0.37 * i * i, 1.0) - 0.5)
    y = signal.lfilter([0.02], [1.0, -0.98], x) + 0.05 * (np.fmod(0.71 * i * i, 1.0) - 0.5)
    return x, y, dt


def scipy_single(x, y, dt):
    kw = dict(fs=1.0 / dt, window="hann", nperseg=4000, noverlap=2000, detrend="constant")
    _, pxy = signal.csd(x, y, **kw)
    _, pxx = signal.welch(x, **kw)
    _, pyy = signal.welch(y, **kw)
    h = pxy / pxx
    coh = np.abs(pxy) ** 2 / (pxx * pyy)
    return h, coh


def main():
    x, y, dt = log_100s_400hz()
    runs = timeit.repeat(lambda: scipy_single(x, y, dt), number=1, repeat=50)
    print(f"SciPy {scipy.__version__}, NumPy {np.__version__}")
    print(f"scipy single window (csd + 2 welch, 4000-sample Hann, 50 %): median {statistics.median(runs) * 1e3:.3f} ms")
    if "--no-rust" in sys.argv:
        return
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    out = subprocess.run(
        ["cargo", "bench", "-p", "helicon-ident", "--bench", "frf"],
        cwd=root, capture_output=True, text=True, check=True,
    ).stdout
    for name, unit, value in re.findall(r"frf_100s_400hz/(\S+)\s+time:\s+\[\S+ \S+ (\S+) (\S+)", out):
        print(f"helicon-ident {name}: median {unit} {value}")


if __name__ == "__main__":
    main()
