#!/usr/bin/env python3
"""Generate cross-validation fixtures for crates/lti (helicon).

Reference implementations: scipy.linalg.solve_discrete_are (DARE), python-control
dlqr / dlqe (LQR gain, Kalman predictor gain and prior covariance), scipy.linalg.expm
(ZOH c2d through the augmented matrix [[A, B], [0, 0]] Ts).

Usage (from the repository root; needs numpy, scipy, control):

    python3 tools/gen_lti_fixtures.py

Writes crates/lti/tests/fixtures/lti_fixtures.json. Fixed seed: the output is
reproducible for a given numpy/scipy/control version (versions are recorded in the file).
CI does not run this script; the output is committed.
"""
import json
import os
import sys

import numpy as np
import scipy
import scipy.linalg as sla
import control

SEED = 20060601
HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
OUT = os.path.join(ROOT, "crates", "lti", "tests", "fixtures", "lti_fixtures.json")
REF = os.path.join(ROOT, "crates", "lti", "tests", "fixtures")


def mat(m):
    m = np.atleast_2d(np.asarray(m, dtype=float))
    return [[float(v) for v in row] for row in m]


def dare_residual(a, b, q, r, x, n=None):
    if n is None:
        n = np.zeros(b.shape)
    k = np.linalg.solve(r + b.T @ x @ b, b.T @ x @ a + n.T)
    atxa = a.T @ x @ a
    corr = (a.T @ x @ b + n) @ k
    res = q + atxa - x - corr
    den = np.linalg.norm(q) + np.linalg.norm(atxa) + np.linalg.norm(x) + np.linalg.norm(corr)
    return np.linalg.norm(res) / den


def random_case(rng, n):
    """A random discrete system with n states; spectral radius drawn in [0.3, 1.6]."""
    m = int(rng.integers(1, min(n, 6) + 1))
    a = rng.standard_normal((n, n))
    rho = max(abs(np.linalg.eigvals(a)))
    target = rng.uniform(0.3, 1.6)
    a *= target / rho
    if n >= 4 and rng.uniform() < 0.15:
        # Make A singular (a dead-beat direction): SDA must not invert A.
        u, s, vt = np.linalg.svd(a)
        s[-1] = 0.0
        a = u @ np.diag(s) @ vt
    b = rng.standard_normal((n, m))
    p = int(rng.integers(1, n + 1))
    cq = rng.standard_normal((p, n))
    q = cq.T @ cq
    rr = rng.standard_normal((m, m))
    r = rr @ rr.T + m * np.eye(m) * rng.uniform(0.1, 2.0)
    nn = None
    if rng.uniform() < 0.3:
        # Cross term with the joint weight [[Q, N], [N', R]] kept PSD: N = Cq' D with
        # D small relative to R.
        d = rng.standard_normal((p, m)) * 0.2
        nn = cq.T @ d
        r = r + d.T @ d  # [[Cq'Cq, Cq'D],[D'Cq, R0 + D'D]] = [Cq D]'[Cq D] + diag(0, R0)
    return a, b, q, r, nn


def kalman_case(rng, a):
    n = a.shape[0]
    pm = int(rng.integers(1, min(n, 6) + 1))
    c = rng.standard_normal((pm, n))
    w = int(rng.integers(1, n + 1))
    g = rng.standard_normal((n, w))
    qq = rng.standard_normal((w, w))
    qn = qq @ qq.T + 0.1 * np.eye(w)
    rv = rng.standard_normal((pm, pm))
    rn = rv @ rv.T + 0.5 * np.eye(pm)
    return c, g, qn, rn


def read_named_csv(path):
    rows = []
    with open(path) as f:
        next(f)
        for line in f:
            if line.strip():
                rows.append([float(v) for v in line.strip().split(",")[1:]])
    return np.array(rows)


def c2d(a, b, ts):
    n, m = b.shape
    aug = np.zeros((n + m, n + m))
    aug[:n, :n] = a * ts
    aug[:n, n:] = b * ts
    e = sla.expm(aug)
    return e[:n, :n], e[:n, n:]


def main():
    rng = np.random.default_rng(SEED)
    dare_cases = []
    sizes = list(range(1, 41)) + [int(v) for v in rng.integers(1, 41, size=12)]
    for idx, n in enumerate(sizes):
        for _attempt in range(20):
            a, b, q, r, nn = random_case(rng, n)
            try:
                x = sla.solve_discrete_are(a, b, q, r, s=nn)
                if nn is None:
                    k, s_, e = control.dlqr(a, b, q, r)
                else:
                    k, s_, e = control.dlqr(a, b, q, r, nn)
            except Exception:  # noqa: BLE001 - resample ill-posed draws
                continue
            res = dare_residual(a, b, q, r, x, nn)
            if res > 1e-11 or max(abs(e)) >= 1.0 - 1e-9:
                continue
            c, g, qn, rn = kalman_case(rng, a)
            try:
                lk, pk, ek = control.dlqe(a, g, c, qn, rn)
            except control.ControlArgument:
                # python-control rejects G Qn G' when rounding makes it asymmetric by more
                # than its own tolerance; then use G = I with the symmetrized W = G Qn G'.
                w = g @ qn @ g.T
                qn = 0.5 * (w + w.T)
                g = np.eye(n)
                lk, pk, ek = control.dlqe(a, g, c, qn, rn)
            resk = dare_residual(a.T, c.T, g @ qn @ g.T, rn, pk)
            if resk > 1e-11:
                continue
            case = {
                "name": f"rand{idx:02d}_n{n}",
                "open_loop_spectral_radius": float(max(abs(np.linalg.eigvals(a)))),
                "A": mat(a), "B": mat(b), "Q": mat(q), "R": mat(r),
                "X": mat(x), "K": mat(k),
                "scipy_residual": float(res),
                "C": mat(c), "Qn": mat(qn), "Rn": mat(rn),
                "L": mat(lk), "P": mat(pk), "kalman_residual": float(resk),
            }
            if nn is not None:
                case["N"] = mat(nn)
            if not np.array_equal(g, np.eye(n)):
                case["G"] = mat(g)  # absent: G = I
            dare_cases.append(case)
            break
        else:
            sys.exit(f"could not draw a well-posed case of size {n}")

    c2d_cases = []
    for idx in range(16):
        n = int(rng.integers(1, 21))
        m = int(rng.integers(1, 5))
        a = rng.standard_normal((n, n)) * rng.uniform(0.1, 50.0)
        b = rng.standard_normal((n, m))
        ts = float(10 ** rng.uniform(-3, 0))
        phi, gam = c2d(a, b, ts)
        c2d_cases.append({"name": f"c2d{idx:02d}_n{n}", "A": mat(a), "B": mat(b), "Ts": ts,
                          "Phi": mat(phi), "Gamma": mat(gam)})

    # Thesis hover model (Appendix E), 400 Hz, weights (14.23), (14.27), rho = 10.
    a = read_named_csv(os.path.join(REF, "thesis_A.csv"))
    b = read_named_csv(os.path.join(REF, "thesis_B.csv"))
    ts = 1.0 / 400.0
    phi, gam = c2d(a, b, ts)
    hs = np.zeros((4, 27))
    for i, j in enumerate([2, 3, 4, 5]):  # psi, u, v, w (14.4)
        hs[i, j] = 1.0
    qy = np.diag([1 / 3**2] * 4)                               # (14.23)
    q2 = np.diag([1 / 0.1**2, 1 / 0.7**2, 1 / 0.7**2, 1 / 0.04**2])  # (14.27)
    rho = 10.0
    q1 = hs.T @ qy @ hs                                         # (14.14)
    r = rho * q2                                                # (14.17)
    alpha = 100 ** (ts / 5.0)                                   # (14.22)
    x = sla.solve_discrete_are(phi, gam, q1, r)
    k, _, e = control.dlqr(phi, gam, q1, r)
    xa = sla.solve_discrete_are(alpha * phi, alpha * gam, q1, r)
    ka, _, _ = control.dlqr(alpha * phi, alpha * gam, q1, r)
    # Integral action (14.31), Qe = Qy (14.35), Qi = 1e-4 Qe (14.36).
    pa = np.zeros((31, 31))
    pa[:27, :27] = phi
    pa[27:, :27] = -hs
    pa[27:, 27:] = np.eye(4)
    ga = np.zeros((31, 4))
    ga[:27, :] = gam
    he = np.hstack([-hs, np.zeros((4, 4))])
    hi = np.hstack([np.zeros((4, 27)), np.eye(4)])
    qe = qy
    qi = 1e-4 * qe
    q1i = he.T @ qe @ he + hi.T @ qi @ hi                       # (14.33)
    xi = sla.solve_discrete_are(alpha * pa, alpha * ga, q1i, r)
    ki, _, _ = control.dlqr(alpha * pa, alpha * ga, q1i, r)
    # Kalman predictor: Hm = [I9 0], Rex = I (15.11), Rey = 1e-3 I (15.12).
    cm = np.hstack([np.eye(9), np.zeros((9, 18))])
    lk, pk, _ = control.dlqe(phi, np.eye(27), cm, np.eye(27), 1e-3 * np.eye(9))
    thesis = {
        "Ts": ts, "Phi": mat(phi), "Gamma": mat(gam), "Hs": mat(hs), "Qy": mat(qy),
        "Q2": mat(q2), "rho": rho, "alpha": alpha, "Q1": mat(q1), "R": mat(r),
        "X": mat(x), "K": mat(k), "residual": float(dare_residual(phi, gam, q1, r, x)),
        "X_alpha": mat(xa), "K_alpha": mat(ka),
        "Qe": mat(qe), "Qi": mat(qi), "X_int": mat(xi), "K_int": mat(ki),
        "residual_int": float(dare_residual(alpha * pa, alpha * ga, q1i, r, xi)),
        "Hm": mat(cm), "Qn": mat(np.eye(27)), "Rn": mat(1e-3 * np.eye(9)),
        "L": mat(lk), "P": mat(pk),
    }
    out = {
        "generator": "tools/gen_lti_fixtures.py",
        "seed": SEED,
        "versions": {"numpy": np.__version__, "scipy": scipy.__version__,
                     "control": control.__version__},
        "dare": dare_cases,
        "c2d": c2d_cases,
        "thesis": thesis,
    }
    with open(OUT, "w") as f:
        json.dump(out, f, separators=(",", ":"))
    print(f"wrote {OUT}: {len(dare_cases)} DARE/dlqr/dlqe cases, {len(c2d_cases)} c2d cases, "
          f"{os.path.getsize(OUT) / 1e6:.2f} MB")
    unstable = sum(1 for c in dare_cases if c["open_loop_spectral_radius"] > 1)
    print(f"open-loop unstable: {unstable}; with cross term N: "
          f"{sum(1 for c in dare_cases if 'N' in c)}")
    print(f"thesis DARE residual (scipy) {thesis['residual']:.2e}, "
          f"integral {thesis['residual_int']:.2e}")


if __name__ == "__main__":
    main()
