"""trim and linearize against the CLI: the same dict as ``trim --json``, the same A.csv/B.csv."""

from __future__ import annotations

import json

import numpy as np
import pytest

import helicon
from helicon import HeliconError

from conftest import read_named_csv

CONDITIONS = [
    ("physical", (0.0, 0.0, 0.0), 0.0, None),
    ("thesis", (0.0, 0.0, 0.0), 0.0, None),
    ("physical", (8.0, 0.0, 0.0), 0.0, None),
    ("physical", (5.0, 1.0, -0.5), 0.7, (1.0, -2.0, 0.0)),
]


def flags(preset, v, yaw, wind):
    f = ["--preset", preset, "--velocity-ned", ",".join(map(repr, v)), "--yaw", repr(yaw)]
    if wind is not None:
        f += ["--wind-ned", ",".join(map(repr, wind))]
    return f


@pytest.mark.parametrize("preset, v, yaw, wind", CONDITIONS)
def test_trim_equals_the_cli_json(cli, preset, v, yaw, wind):
    want = json.loads(cli("trim", "--json", *flags(preset, v, yaw, wind)).stdout)
    got = helicon.trim(preset, v, yaw=yaw, wind_ned=wind)
    assert got == want


def test_an_unphysical_trim_is_returned_with_its_violations(cli):
    v = (0.0, 0.0, 4.0)  # a 4 m/s descent: vortex-ring state
    p = cli("trim", "--json", *flags("physical", v, 0.0, None), check=False)
    assert p.returncode != 0  # the CLI fails without --allow-unphysical, after printing
    got = helicon.trim(velocity_ned=v)
    assert got == json.loads(p.stdout)
    assert got["validity"]["physical"] is False
    q = {x["quantity"] for x in got["validity"]["violations"]}
    assert "descent_ratio_mr" in q


def test_trim_with_params_file_equals_the_cli(cli, tmp_path):
    f = tmp_path / "heavy.toml"
    f.write_text("[body]\nmass_kg = 15.5\n")
    want = json.loads(cli("trim", "--json", "--params", f).stdout)
    assert helicon.trim(params=f) == want
    assert helicon.trim(params=helicon.Params.from_file(f)) == want
    assert helicon.trim(params=helicon.Params().replace({"body.mass_kg": 15.5})) == want


@pytest.mark.parametrize("thesis_inflow", [False, True])
@pytest.mark.parametrize("preset, v, yaw, wind", CONDITIONS[:3])
def test_linearize_equals_the_cli_csv(cli, tmp_path, preset, v, yaw, wind, thesis_inflow):
    out = tmp_path / "lin"
    args = ["linearize", *flags(preset, v, yaw, wind), "--discrete", "0.0025", "--out", out]
    if thesis_inflow:
        args.append("--thesis-inflow")
    cli(*args)
    A, B, Phi, Gamma = helicon.linearize(preset, v, thesis_inflow=thesis_inflow, dt=0.0025, yaw=yaw, wind_ned=wind)
    for name, m in [("A", A), ("B", B), ("Phi", Phi), ("Gamma", Gamma)]:
        ref = read_named_csv(out / f"{name}.csv")
        assert m.shape == ref.shape
        assert np.array_equal(m, ref), name  # CSV holds the shortest round-trip text: exact
    A2, B2 = helicon.linearize(preset, v, thesis_inflow=thesis_inflow, yaw=yaw, wind_ned=wind)
    assert np.array_equal(A2, A) and np.array_equal(B2, B)


def test_the_csv_header_is_the_reduced_state_order(cli, tmp_path):
    cli("linearize", "--out", tmp_path)
    head = (tmp_path / "A.csv").read_text().splitlines()[0].split(",")
    assert head[1:] == helicon.reduced_state_names()
    head = (tmp_path / "B.csv").read_text().splitlines()[0].split(",")
    assert head[1:] == helicon.input_names()


def test_linearize_refuses_an_unphysical_trim_unless_allowed():
    with pytest.raises(HeliconError, match="refusing to linearize: the trim is not physical"):
        helicon.linearize(velocity_ned=(0.0, 0.0, 4.0))
    A, B = helicon.linearize(velocity_ned=(0.0, 0.0, 4.0), allow_unphysical=True)
    assert A.shape == (27, 27) and np.isfinite(A).all()


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(velocity_ned=(150.0, 0.0, 0.0)), "beyond"),
        (dict(velocity_ned=(np.nan, 0.0, 0.0)), "not finite"),
        (dict(velocity_ned=(1.0, 0.0)), r"velocity_ned: shape \[2\]"),
        (dict(yaw=1e9), "yaw"),
        (dict(yaw_rate=0.1), "yaw_rate"),
        (dict(preset="nope"), "unknown model preset"),
        (dict(params=42), "params: expected"),
        (dict(params="/nonexistent/p.toml"), "/nonexistent/p.toml"),
    ],
)
def test_bad_conditions_raise(kwargs, message):
    with pytest.raises(HeliconError, match=message):
        helicon.trim(**kwargs)


def test_bad_sample_time_raises():
    with pytest.raises(HeliconError, match="dt = 0"):
        helicon.linearize(dt=0.0)
    with pytest.raises(HeliconError, match="dt = -1"):
        helicon.linearize(dt=-1.0)
