#!/usr/bin/env python3
"""Reference spectra for helicon-ident, from SciPy.

Writes crates/ident/tests/fixtures/scipy_csd.json: two channels x, y (the
numbers themselves, so the test needs neither Python nor the same RNG) and,
for several window settings, SciPy's csd(x, y), welch(x), welch(y) and
coherence(x, y) with window="hann" (periodic), detrend="constant",
scaling="density", one-sided. Run from the repository root:
    python3 tools/gen_ident_fixtures.py
"""
import json
import os

import numpy as np
import scipy
from scipy import signal

OUT = os.path.join("crates", "ident", "tests", "fixtures", "scipy_csd.json")


def main():
    rng = np.random.default_rng(20061114)
    fs = 400.0
    n = 4096
    x = rng.standard_normal(n)
    # y: x through a second-order filter plus noise and an offset (the
    # per-segment mean removal is part of the comparison).
    b, a = signal.butter(2, 20.0, fs=fs)
    y = signal.lfilter(b, a, x) + 0.3 * rng.standard_normal(n) + 1.5
    cases = []
    for nperseg, noverlap in [(256, 128), (200, 50), (1024, 768)]:
        kw = dict(fs=fs, window="hann", nperseg=nperseg, noverlap=noverlap,
                  detrend="constant", scaling="density")
        f, pxy = signal.csd(x, y, **kw)
        _, pxx = signal.welch(x, **kw)
        _, pyy = signal.welch(y, **kw)
        _, cxy = signal.coherence(x, y, fs=fs, window="hann", nperseg=nperseg,
                                  noverlap=noverlap, detrend="constant")
        cases.append({
            "nperseg": nperseg,
            "noverlap": noverlap,
            "f_hz": f.tolist(),
            "pxx": pxx.tolist(),
            "pyy": pyy.tolist(),
            "pxy_re": pxy.real.tolist(),
            "pxy_im": pxy.imag.tolist(),
            "cxy": cxy.tolist(),
        })
    doc = {
        "generator": "tools/gen_ident_fixtures.py",
        "scipy": scipy.__version__,
        "numpy": np.__version__,
        "fs_hz": fs,
        "x": x.tolist(),
        "y": y.tolist(),
        "cases": cases,
    }
    os.makedirs(os.path.dirname(OUT), exist_ok=True)
    with open(OUT, "w") as fh:
        json.dump(doc, fh)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
