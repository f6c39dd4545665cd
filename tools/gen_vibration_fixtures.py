"""Reference Butterworth low-pass filters for helicon's IMU vibration chain.

Writes crates/sim/tests/fixtures/butterworth_scipy.json: for each (order,
cut-off, sample rate) the SciPy design `butter(order, fc, fs=fs, output='sos')`
(bilinear transform with pre-warping), its impulse response (first 200
samples, `sosfilt`) and its gain at a grid of frequencies (`sosfreqz`).
The test compares helicon's own design (crates/sim/src/vibration.rs) against
the responses, which do not depend on how the sections are ordered.

Run: python3 tools/gen_vibration_fixtures.py  (SciPy >= 1.4)
"""
import json
import pathlib

import numpy as np
import scipy
from scipy import signal

CASES = [(1, 50.0, 8000.0), (2, 1000.0, 8000.0), (3, 120.0, 4000.0),
         (4, 50.0, 8000.0), (5, 50.0, 8000.0), (5, 200.0, 8000.0),
         (6, 30.0, 2000.0), (7, 400.0, 16000.0), (8, 50.0, 8000.0)]

out = {"generator": f"scipy {scipy.__version__}", "cases": []}
for order, fc, fs in CASES:
    sos = signal.butter(order, fc, btype="low", fs=fs, output="sos")
    x = np.zeros(200)
    x[0] = 1.0
    h = signal.sosfilt(sos, x)
    freqs = np.array([0.0, 0.25 * fc, 0.5 * fc, fc, 1.5 * fc, 2.0 * fc, 4.0 * fc, 0.4 * fs])
    _, resp = signal.sosfreqz(sos, worN=freqs, fs=fs)
    out["cases"].append({
        "order": order, "cutoff_hz": fc, "sample_rate_hz": fs,
        "impulse": h.tolist(), "freqs_hz": freqs.tolist(),
        "gain": np.abs(resp).tolist(),
    })

path = pathlib.Path(__file__).resolve().parent.parent / "crates/sim/tests/fixtures/butterworth_scipy.json"
path.write_text(json.dumps(out) + "\n")
print(f"wrote {path}")
