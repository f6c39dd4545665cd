#!/usr/bin/env python3
"""Reference frequency responses of state-space models for helicon-ident's
state-space fit, from SciPy.

Writes crates/ident/tests/fixtures/ssfit_freqresp.json: for each model its
A, B, C, D, input delays and, for every input i and output o, SciPy's
signal.freqresp of the single-input single-output system
(A, B[:, i], C[o, :], D[o, i]) on a log grid, times exp(-j w tau_i) (numpy).
Run from the repository root:
    python3 tools/gen_ssfit_fixtures.py
"""
import json
import os

import numpy as np
import scipy
from scipy import signal

OUT = os.path.join("crates", "ident", "tests", "fixtures", "ssfit_freqresp.json")


def hover():
    # Hover longitudinal u-q-theta model (X_theta = -g), one input.
    xu, mu, mq, md, xd, g = -0.3, 0.05, -3.0, 20.0, -4.0, 9.81
    a = [[xu, 0.0, -g], [mu, mq, 0.0], [0.0, 1.0, 0.0]]
    b = [[xd], [md], [0.0]]
    c = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
    d = [[0.0], [0.0]]
    return {"name": "hover_u_q_theta", "a": a, "b": b, "c": c, "d": d,
            "delay_s": [0.02]}


def coupled():
    # A coupled 4-state, 2-input, 3-output system with a direct term:
    # stable, lightly damped modes, fixed random couplings.
    rng = np.random.default_rng(20061130)
    a = np.array([[0.0, 1.0, 0.0, 0.0],
                  [-25.0, -2.0, 3.0, 0.5],
                  [0.0, 0.0, 0.0, 1.0],
                  [4.0, -0.3, -64.0, -1.2]])
    b = rng.standard_normal((4, 2))
    c = rng.standard_normal((3, 4))
    d = np.array([[0.0, 0.1], [0.0, 0.0], [-0.05, 0.0]])
    return {"name": "coupled_4x2x3", "a": a.tolist(), "b": b.tolist(),
            "c": c.tolist(), "d": d.tolist(), "delay_s": [0.0, 0.035]}


def main():
    omega = np.logspace(-1, 2, 40)
    models = []
    for m in [hover(), coupled()]:
        a, b, c, d = (np.array(m[k], dtype=float) for k in "abcd")
        resp = []
        for i in range(b.shape[1]):
            for o in range(c.shape[0]):
                sys = signal.StateSpace(a, b[:, i:i + 1], c[o:o + 1, :], d[o:o + 1, i:i + 1])
                _, h = signal.freqresp(sys, w=omega)
                h = h * np.exp(-1j * omega * m["delay_s"][i])
                resp.append({"input": i, "output": o,
                             "re": h.real.tolist(), "im": h.imag.tolist()})
        m["omega_rad_s"] = omega.tolist()
        m["responses"] = resp
        models.append(m)
    doc = {"generator": "tools/gen_ssfit_fixtures.py", "scipy": scipy.__version__,
           "models": models}
    with open(OUT, "w") as f:
        json.dump(doc, f, indent=1)
        f.write("\n")
    print("wrote", OUT)


if __name__ == "__main__":
    main()
