"""helicon.mc against ``helicon mc``: the runs.csv rows, traces.csv and stats.json."""

from __future__ import annotations

import math

import numpy as np
import pytest

import helicon
from helicon import HeliconError

from conftest import read_csv_rows, read_json

CAMPAIGN = """
name = "py-mc"
runs = 4
seed = 5
trace_rate_hz = 20.0

[scenario]
name = "hover-gust"
duration_s = 1.0
[scenario.wind]
seed = 1
[scenario.wind.thesis]
max_gust_m_s = 1.0

[[dispersion]]
param = "body.mass_kg"
distribution = "normal"
kind = "relative"
sigma = 0.05

[[dispersion]]
param = "main_rotor.omega_rad_s"
distribution = "uniform"
kind = "relative"
half_width = 0.05
"""


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    d = tmp_path_factory.mktemp("mc")
    f = d / "campaign.toml"
    f.write_text(CAMPAIGN)
    return f


def test_runs_equal_the_cli(cli, campaign, tmp_path):
    out = tmp_path / "out"
    cli("mc", campaign, "--out", out, "--threads", "2")
    r = helicon.mc(campaign, threads=1)
    assert len(r) == 4 and r.dispersed == ["body.mass_kg", "main_rotor.omega_rad_s"]
    rows = read_csv_rows(out / "runs.csv")
    assert list(rows[0]) == list(r.runs)
    for i, row in enumerate(rows):
        for k, text in row.items():
            got = r.runs[k][i]
            if k in ("outcome", "termination", "reason"):
                assert got == text, k
            elif text == "":
                assert math.isnan(got), k
            else:
                assert float(got) == float(text), k
    traces = read_csv_rows(out / "traces.csv")
    for i in range(4):
        mine = r.traces[i]
        theirs = np.array([[float(t[k]) for k in list(t)[1:]] for t in traces if int(t["index"]) == i])
        assert mine.shape == theirs.shape and np.array_equal(mine, theirs)
    assert r.stats == read_json(out / "stats.json")


def test_threads_do_not_change_the_runs(campaign):
    a = helicon.mc(campaign, runs=3, threads=1)
    b = helicon.mc(campaign, runs=3, threads=2)
    assert list(a.runs) == list(b.runs)
    for k, v in a.runs.items():
        if isinstance(v, np.ndarray):
            assert np.array_equal(v, b.runs[k], equal_nan=v.dtype.kind == "f"), k
        else:
            assert v == b.runs[k], k
    assert a.records[0]["index"] == 0 and isinstance(a.records[0]["outcome"], str)


def test_overrides_and_accessors(campaign):
    r = helicon.mc(campaign, runs=2, seed=9, duration=0.5)
    assert np.all(r.runs["t_end_s"] == 0.5)
    base = helicon.mc(campaign, runs=2)
    assert r.runs["body.mass_kg"][0] != base.runs["body.mass_kg"][0]
    assert "2 runs" in repr(r)
    pd = pytest.importorskip("pandas")
    df = r.to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.index) == [0, 1]


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(runs=0), "runs = 0"),
        (dict(runs=-3), "runs"),
        (dict(threads=0), "threads = 0"),
        (dict(duration=0.0), "duration"),
        (dict(params=12), "params"),
    ],
)
def test_bad_arguments_raise(campaign, kwargs, message):
    with pytest.raises(HeliconError, match=message):
        helicon.mc(campaign, **kwargs)


def test_bad_campaigns_raise(tmp_path):
    with pytest.raises(HeliconError, match="missing.toml"):
        helicon.mc(tmp_path / "missing.toml")
    with pytest.raises(HeliconError, match="campaign"):
        helicon.mc(42)
    f = tmp_path / "bad.toml"
    f.write_text(CAMPAIGN.replace('param = "body.mass_kg"', 'param = "body.nope"'))
    with pytest.raises(HeliconError, match="body.nope"):
        helicon.mc(f)
