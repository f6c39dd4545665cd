"""helicon.sim against ``helicon sim``: log.csv and summary.json identical."""

from __future__ import annotations

import numpy as np
import pytest

import helicon
from helicon import HeliconError

from conftest import read_columns, read_json

SCENARIOS = [
    ("scenarios/demo.toml", 2.0, None),
    ("scenarios/thesis-fig14-5.toml", 1.0, None),  # four [[case]]s
    ("scenarios/thesis-appendix-f.toml", 3.0, None),  # the thesis's failure
    ("scenarios/beyond-physical-turbulence.toml", 1.5, 7),  # sensors, fusion, turbulence
]


def cli_runs(cli, tmp_path, scenario, duration, seed):
    out = tmp_path / "run"
    args = ["sim", scenario, "--duration", repr(duration), "--out", out]
    if seed is not None:
        args += ["--seed", str(seed)]
    cli(*args)
    return out


@pytest.mark.parametrize("scenario, duration, seed", SCENARIOS)
def test_logs_and_summaries_equal_the_cli(cli, repo, tmp_path, scenario, duration, seed):
    out = cli_runs(cli, tmp_path, scenario, duration, seed)
    results = helicon.sim(repo / scenario, duration=duration, seed=seed)
    many = len(results) > 1
    for r in results:
        folder = out / r.label if many else out
        want = read_columns(folder / "log.csv")
        assert list(r.log) == list(want) == helicon.log_columns()
        for name, col in want.items():
            assert np.array_equal(r.log[name], col), (r.label, name)
        summary = read_json(folder / "summary.json")
        assert r.summary == summary
        assert r.outcome == summary["outcome"]


def test_a_scenario_object_and_params_objects_fly_the_same(repo, tmp_path):
    path = repo / "scenarios/demo.toml"
    a = helicon.sim(path, duration=0.5)[0]
    b = helicon.sim(helicon.Scenario.from_file(path), duration=0.5)[0]
    assert all(np.array_equal(a.log[k], b.log[k]) for k in a.log)
    f = tmp_path / "light.toml"
    f.write_text("[body]\nmass_kg = 13.0\n")
    c = helicon.sim(path, duration=0.5, params=f)[0]
    d = helicon.sim(path, duration=0.5, params=helicon.Params().replace({"body.mass_kg": 13.0}))[0]
    assert all(np.array_equal(c.log[k], d.log[k]) for k in c.log)
    assert not np.array_equal(a.log["S_col"], c.log["S_col"])
    assert c.summary["parameter_hash"] == d.summary["parameter_hash"] != a.summary["parameter_hash"]


def test_result_accessors(repo):
    r = helicon.sim(repo / "scenarios/thesis-fig14-5.toml", duration=0.2)
    s = helicon.Scenario.from_file(repo / "scenarios/thesis-fig14-5.toml")
    assert [x.label for x in r] == s.cases == ["a", "b", "c", "d"]
    assert r[0].name == f"{s.name}-a"
    assert np.array_equal(r[0].t_s, r[0].log["t_s"])
    assert "completed" in repr(r[0])
    pd = pytest.importorskip("pandas")
    df = r[0].to_pandas()
    assert isinstance(df, pd.DataFrame) and list(df.columns) == helicon.log_columns()


def test_scenario_from_toml_and_back():
    s = helicon.Scenario.from_toml('name = "h"\nduration_s = 0.3\n')
    assert (s.name, s.duration_s, s.preset, s.cases) == ("h", 0.3, "physical", ["h"])
    again = helicon.Scenario.from_toml(s.to_toml())
    assert again.to_toml() == s.to_toml()
    r = helicon.sim(s)[0]
    assert r.outcome == "completed" and r.log["t_s"][-1] == pytest.approx(0.3)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(duration=-1.0), "duration_s"),
        (dict(duration=float("nan")), "duration_s"),
        (dict(seed=-1), "seed"),
        (dict(seed=1.5), "seed"),
        (dict(params=3), "params"),
        (dict(params="/nonexistent/p.toml"), "/nonexistent/p.toml"),
    ],
)
def test_bad_overrides_raise(repo, kwargs, message):
    with pytest.raises(HeliconError, match=message):
        helicon.sim(repo / "scenarios/demo.toml", **kwargs)


def test_bad_scenarios_raise(tmp_path):
    with pytest.raises(HeliconError, match="missing.toml"):
        helicon.sim(tmp_path / "missing.toml")
    f = tmp_path / "bad.toml"
    f.write_text("duration_s = 1.0\nnot_a_key = 3\n")
    with pytest.raises(HeliconError, match="not_a_key"):
        helicon.sim(f)
    with pytest.raises(HeliconError, match="bad.toml"):
        helicon.Scenario.from_file(f)
