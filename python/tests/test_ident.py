"""helicon.ident.frf against ``helicon ident frf`` and against a known system."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.signal

import helicon
from helicon import HeliconError

from conftest import read_csv_rows

DT = 0.01


def record(n=6000, seed=3):
    """A random input through a 2nd-order low-pass (4 Hz-ish), discretized by Tustin."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * DT
    u = rng.standard_normal(n)
    wn, z = 12.0, 0.3
    b, a = scipy.signal.bilinear([wn * wn], [1.0, 2 * z * wn, wn * wn], fs=1 / DT)
    y = scipy.signal.lfilter(b, a, u)
    return t, u, y, (b, a)


def test_equals_the_cli(cli, tmp_path):
    t, u, y, _ = record()
    y2 = -0.5 * y + 0.01 * np.sin(t)
    f = tmp_path / "log.csv"
    with open(f, "w") as fh:
        fh.write("t_s,u,y,y2\n")
        for row in zip(t, u, y, y2):
            fh.write(",".join(repr(float(v)) for v in row) + "\n")
    out = tmp_path / "frf"
    cli("ident", "frf", f, "--input", "u", "--output", "y,y2", "--out", out)
    rows = read_csv_rows(out / "frf.csv")
    got = helicon.ident.frf(t, u, np.column_stack([y, y2]))
    for k, name in enumerate(["y", "y2"]):
        mine = got[k]
        theirs = [r for r in rows if r["output"] == name]
        for col in ["omega_rad_s", "mag_db", "phase_deg", "coherence", "random_error"]:
            assert np.array_equal(mine[col], np.array([float(r[col]) for r in theirs])), (name, col)


def test_a_known_system_is_recovered():
    t, u, y, (b, a) = record()
    r = helicon.ident.frf(t, u, y, 1.0, 60.0, points=50)
    assert set(r) == {"omega_rad_s", "mag_db", "phase_deg", "coherence", "random_error"}
    w = r["omega_rad_s"]
    assert w[0] == pytest.approx(1.0) and w[-1] == pytest.approx(60.0) and len(w) == 50
    _, h = scipy.signal.freqz(b, a, worN=w * DT)
    good = r["coherence"] > 0.95
    assert good.sum() > 40
    assert np.max(np.abs(r["mag_db"][good] - 20 * np.log10(np.abs(h[good])))) < 0.5


def test_conditioned_on_a_correlated_input():
    rng = np.random.default_rng(8)
    n = 8000
    t = np.arange(n) * DT
    u1 = rng.standard_normal(n)
    u2 = 0.6 * u1 + 0.8 * rng.standard_normal(n)
    y = 2.0 * u1 - 1.0 * u2
    naive = helicon.ident.frf(t, u1, y)
    cond = helicon.ident.frf(t, u1, y, conditioned_on=u2)
    assert np.max(np.abs(cond["mag_db"] - 20 * np.log10(2.0))) < 1e-6
    assert np.max(np.abs(naive["mag_db"] - 20 * np.log10(2.0))) > 1.0


@pytest.mark.parametrize(
    "mutate, message",
    [
        (lambda t, u, y: (t[::-1], u, y), "does not increase"),
        (lambda t, u, y: (t, u[:-1], y), "u: 5999 samples"),
        (lambda t, u, y: (t, u, np.where(np.arange(len(y)) == 7, np.nan, y)), r"y\[7\]"),
        (lambda t, u, y: (t[:20], u[:20], y[:20]), "too short"),
        (lambda t, u, y: (t, u, y.reshape(-1, 2, 1)), "shape"),
    ],
)
def test_bad_records_raise(mutate, message):
    t, u, y, _ = record()
    with pytest.raises(HeliconError, match=message):
        helicon.ident.frf(*mutate(t, u, y))


def test_bad_options_raise():
    t, u, y, _ = record()
    with pytest.raises(HeliconError, match="Nyquist"):
        helicon.ident.frf(t, u, y, 1.0, 1000.0)
    with pytest.raises(HeliconError, match="windows"):
        helicon.ident.frf(t, u, y, windows=0)
    with pytest.raises(HeliconError, match="points"):
        helicon.ident.frf(t, u, y, points=1)
    with pytest.raises(HeliconError, match="omega"):
        helicon.ident.frf(t, u, y, 10.0, 5.0)
