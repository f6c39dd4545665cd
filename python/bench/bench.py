"""Benchmarks of the Python package (medians of repeated wall-clock timings).

1. ``Model.derivative`` on a batch of 10^5 states (one call, GIL released,
   rows spread over the cores) against a per-row Python loop of single
   calls on the same states (the loop is what a user writes without a
   batch API), and the bit-identity of the two.
2. ``helicon.linearize`` in-process against the CLI's
   ``helicon linearize --out DIR`` (a process per call, which also writes
   A.csv, B.csv, poles.csv and summary.json and computes the ranks).

There is no NumPy implementation of this model to compare with (the thesis
model's blade-element integrals, inflow solution and flapping are only in
helicon-model); the loop of single calls is the per-row baseline.

    python python/bench/bench.py [--rows 100000] [--repeat 5] [--cli target/release/helicon]
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

import helicon

REPO = Path(__file__).resolve().parents[2]


def median_time(f, repeat: int) -> float:
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def states(n: int):
    t = helicon.trim(velocity_ned=(5.0, 0.0, 0.0))
    names = helicon.state_names()
    x0 = np.zeros(30)
    for k, v in t["state"].items():
        x0[names.index(k)] = v
    u0 = np.array([t["input"][k] for k in helicon.input_names()])
    rng = np.random.default_rng(0)
    x = x0 + 0.02 * rng.standard_normal((n, 30))
    u = u0 + 0.01 * rng.standard_normal((n, 4))
    return x, u


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--loop-repeat", type=int, default=3)
    ap.add_argument("--cli", type=Path, default=REPO / "target" / "release" / "helicon")
    a = ap.parse_args()

    print(f"helicon {helicon.__version__}, numpy {np.__version__}, {os.cpu_count()} CPU(s)")
    m = helicon.Model()
    x, u = states(a.rows)
    batch = m.derivative(x, u)
    t_batch = median_time(lambda: m.derivative(x, u), a.repeat)

    def loop():
        out = np.empty_like(x)
        for i in range(len(x)):
            out[i] = m.derivative(x[i], u[i])
        return out

    same = loop().tobytes() == batch.tobytes()
    t_loop = median_time(loop, a.loop_repeat)
    print(f"\nModel.derivative, {a.rows} states (median of {a.repeat} / {a.loop_repeat}):")
    print(f"  batch (N, 30) call:       {t_batch * 1e3:9.1f} ms  ({t_batch / a.rows * 1e9:7.0f} ns/state)")
    print(f"  per-row Python loop:      {t_loop * 1e3:9.1f} ms  ({t_loop / a.rows * 1e9:7.0f} ns/state)")
    print(f"  speed-up:                 {t_loop / t_batch:9.1f} x; batch == loop bit for bit: {same}")

    v = (5.0, 0.0, 0.0)
    t_py = median_time(lambda: helicon.linearize(velocity_ned=v), a.repeat * 4)
    print(f"\nlinearize at 5 m/s forward (median of {a.repeat * 4}):")
    print(f"  helicon.linearize:        {t_py * 1e3:9.2f} ms")
    if a.cli.exists():
        with tempfile.TemporaryDirectory() as d:
            cmd = [str(a.cli), "linearize", "--velocity-ned", "5,0,0", "--out", d]

            def run_cli():
                subprocess.run(cmd, check=True, capture_output=True)

            t_cli = median_time(run_cli, a.repeat * 4)
            t_true = median_time(lambda: subprocess.run(["true"], check=True), a.repeat * 4)
        print(f"  helicon linearize (CLI):  {t_cli * 1e3:9.2f} ms  (a process start alone: {t_true * 1e3:.2f} ms)")
        print(f"  speed-up:                 {t_cli / t_py:9.1f} x")
    else:
        print(f"  (no CLI at {a.cli}: cargo build --release -p helicon-cli)")


if __name__ == "__main__":
    main()
