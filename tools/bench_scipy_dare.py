#!/usr/bin/env python3
"""Time scipy.linalg.solve_discrete_are on the problems of crates/lti/benches/dare.rs.

Problems: the thesis hover model (Appendix E, 27 states) discretized at 400 Hz (ZOH by
expm), weights (14.23)/(14.27) with rho = 10 (Bryson, (14.14)-(14.17)); the same with the
pincer alpha = 100**(Ts/5) (14.22); and the integral-augmented 31-state system (14.31) with
Qe = Qy (14.35), Qi = 1e-4 Qe (14.36), pincer alpha.

Usage: python3 tools/bench_scipy_dare.py   (prints median ms per solve; compare with
`cargo bench -p helicon-lti --bench dare`).
"""
import os
import statistics
import timeit

import numpy as np
import scipy
import scipy.linalg as sla

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
FIX = os.path.join(ROOT, "crates", "lti", "tests", "fixtures")


def read_named_csv(path):
    with open(path) as f:
        next(f)
        return np.array([[float(v) for v in line.strip().split(",")[1:]] for line in f if line.strip()])


def problems():
    a = read_named_csv(os.path.join(FIX, "thesis_A.csv"))
    b = read_named_csv(os.path.join(FIX, "thesis_B.csv"))
    ts = 1.0 / 400.0
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n] = a * ts
    aug[:n, n:] = b * ts
    e = sla.expm(aug)
    phi, gam = e[:n, :n], e[:n, n:]
    hs = np.zeros((4, 27))
    for i, j in enumerate([2, 3, 4, 5]):
        hs[i, j] = 1.0
    qy = np.diag([1 / 9.0] * 4)
    r = 10.0 * np.diag([1 / 0.1**2, 1 / 0.7**2, 1 / 0.7**2, 1 / 0.04**2])
    q1 = hs.T @ qy @ hs
    alpha = 100 ** (ts / 5.0)
    pa = np.zeros((31, 31))
    pa[:27, :27] = phi
    pa[27:, :27] = -hs
    pa[27:, 27:] = np.eye(4)
    ga = np.vstack([gam, np.zeros((4, 4))])
    he = np.hstack([-hs, np.zeros((4, 4))])
    hi = np.hstack([np.zeros((4, 27)), np.eye(4)])
    q1i = he.T @ qy @ he + hi.T @ (1e-4 * qy) @ hi
    return {
        "dare_thesis_27": (phi, gam, q1, r),
        "dare_thesis_27_pincer": (alpha * phi, alpha * gam, q1, r),
        "dare_thesis_31_integral_pincer": (alpha * pa, alpha * ga, q1i, r),
    }


def main():
    print(f"scipy {scipy.__version__}, numpy {np.__version__}")
    for name, (a, b, q, r) in problems().items():
        sla.solve_discrete_are(a, b, q, r)  # warm-up
        number = 20
        runs = timeit.repeat(lambda: sla.solve_discrete_are(a, b, q, r), number=number, repeat=15)
        per = [t / number * 1e3 for t in runs]
        print(f"{name}: median {statistics.median(per):.3f} ms  (min {min(per):.3f} ms)")


if __name__ == "__main__":
    main()
