"""The model: names, single and batch derivative, parameters, bad input."""

from __future__ import annotations

import copy
import pickle

import numpy as np
import pytest

import helicon
from helicon import HeliconError


def hover_state():
    t = helicon.trim()
    names = helicon.state_names()
    x = np.zeros(30)
    for k, v in t["state"].items():
        x[names.index(k)] = v
    u = np.array([t["input"][n] for n in helicon.input_names()])
    return x, u


def test_names_and_version():
    assert isinstance(helicon.__version__, str) and helicon.__version__.count(".") == 2
    names = helicon.state_names()
    assert len(names) == 30 and names[:6] == ["x", "y", "z", "phi", "theta", "psi"]
    assert helicon.reduced_state_names() == names[3:]
    assert helicon.input_names() == ["S_col", "S_lat", "S_lon", "S_tr"]
    assert len(helicon.state_units()) == 30
    assert helicon.log_columns()[0] == "t_s" and helicon.log_units()["t_s"] == "s"
    assert issubclass(HeliconError, ValueError)


def test_derivative_at_the_trim_is_an_equilibrium():
    x, u = hover_state()
    xd = helicon.Model().derivative(x, u)
    assert xd.shape == (30,) and xd.dtype == np.float64
    # position rates are the velocity (zero in hover); the rest balances
    assert np.max(np.abs(xd)) < 1e-8


def test_batch_equals_single_bit_for_bit():
    rng = np.random.default_rng(1)
    x0, u0 = hover_state()
    n = 2000
    x = x0 + 0.05 * rng.standard_normal((n, 30))
    u = u0 + 0.02 * rng.standard_normal((n, 4))
    w = rng.standard_normal((n, 3))
    m = helicon.Model(preset="thesis")
    batch = m.derivative(x, u, w)
    assert batch.shape == (n, 30)
    single = np.stack([m.derivative(x[i], u[i], w[i]) for i in range(n)])
    assert batch.tobytes() == single.tobytes()


def test_broadcast_u_and_wind_and_empty_batch():
    x0, u0 = hover_state()
    x = np.tile(x0, (5, 1))
    m = helicon.Model()
    a = m.derivative(x, u0, [1.0, 0.0, 0.0])
    b = m.derivative(x, np.tile(u0, (5, 1)), np.tile([1.0, 0.0, 0.0], (5, 1)))
    assert a.tobytes() == b.tobytes()
    assert m.derivative(np.zeros((0, 30)), u0).shape == (0, 30)


def test_array_likes_are_converted():
    x0, u0 = hover_state()
    m = helicon.Model()
    ref = m.derivative(x0, u0)
    assert m.derivative(list(x0), tuple(u0)).tobytes() == ref.tobytes()
    big = np.zeros((30, 2))
    big[:, 0] = x0
    # a non-contiguous column view
    assert m.derivative(big[:, 0], u0).tobytes() == ref.tobytes()


@pytest.mark.parametrize(
    "x, u, wind, message",
    [
        (np.zeros(29), np.zeros(4), None, "x: shape [29]"),
        (np.zeros((3, 30)), np.zeros((2, 4)), None, "u: shape [2, 4]"),
        (np.zeros(30), np.zeros((1, 4)), None, "u: shape [1, 4]"),
        (np.zeros((2, 30)), np.zeros(4), np.zeros(2), "wind: shape [2]"),
        (np.zeros((2, 2, 30)), np.zeros(4), None, "x: shape"),
        ("abc", np.zeros(4), None, "x: not an array of numbers"),
    ],
)
def test_bad_shapes_raise(x, u, wind, message):
    with pytest.raises(HeliconError, match=message.replace("[", r"\[").replace("]", r"\]")):
        helicon.Model().derivative(x, u, wind)


def test_non_finite_and_singular_states_raise_naming_the_row():
    x = np.zeros((4, 30))
    x[2, 7] = np.nan
    with pytest.raises(HeliconError, match=r"row 2: non-finite state `v`"):
        helicon.Model().derivative(x, np.zeros(4))
    x = np.zeros(30)
    x[4] = np.pi / 2
    with pytest.raises(HeliconError, match="singularity"):
        helicon.Model().derivative(x, np.zeros(4))
    with pytest.raises(HeliconError, match="non-finite input"):
        helicon.Model().derivative(np.zeros(30), [np.inf, 0, 0, 0])


def test_presets_and_bad_preset():
    assert helicon.Model("thesis").preset == "thesis"
    with pytest.raises(HeliconError, match="unknown model preset `nope`"):
        helicon.Model("nope")


def test_params_default_dict_toml_roundtrip(tmp_path):
    p = helicon.Params()
    assert p == helicon.Params() and p["body.mass_kg"] == 14.0
    d = p.to_dict()
    assert d["servo"]["tail"]["s_min"] == -0.37 and d["main_rotor"]["blades"] == 2
    assert d["yaw_gyro"]["enabled"] is False
    # 81 of the thesis model, 22 of the ground blocks (landing gear, ground effect, drivetrain)
    assert len(p) == len(helicon.Params.keys()) == 103 and "body.mass_kg" in p
    f = tmp_path / "heli.toml"
    f.write_text(p.replace({"body": {"mass_kg": 12.5}}).to_toml())
    q = helicon.Params.from_file(f)
    assert q["body.mass_kg"] == 12.5 and q != p
    assert helicon.Params.from_toml(q.to_toml()) == q
    assert pickle.loads(pickle.dumps(q)) == q and copy.deepcopy(q) == q
    assert helicon.Params.describe("body.mass_kg")["unit"] == "kg"


def test_params_edits_are_validated_and_atomic():
    p = helicon.Params()
    p["body.mass_kg"] = 12
    assert p["body.mass_kg"] == 12.0
    with pytest.raises(HeliconError, match=r"body.mass_kg` = -1.0 is invalid: must be > 0"):
        p["body.mass_kg"] = -1.0
    assert p["body.mass_kg"] == 12.0
    with pytest.raises(HeliconError, match="must be < s_max"):
        p.update({"servo.tail.s_min": 0.9, "body.mass_kg": 13.0})
    assert p["body.mass_kg"] == 12.0  # all or none
    with pytest.raises(HeliconError, match="unknown key `body.mas_kg`"):
        p["body.mas_kg"] = 1.0
    with pytest.raises(KeyError):
        p["nope.key"]
    with pytest.raises(HeliconError, match="must be a number, found boolean"):
        p["body.mass_kg"] = True
    with pytest.raises(HeliconError, match="must be finite"):
        p["body.mass_kg"] = float("nan")
    p["yaw_gyro.enabled"] = True
    assert p["yaw_gyro.enabled"] is True
    p["main_rotor.blades"] = np.float64(3)
    assert p["main_rotor.blades"] == 3


def test_params_file_errors_name_file_and_line(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("[body]\nmass_kg = 14.0\nixx_kg_m2 = -2\n")
    with pytest.raises(HeliconError, match=r"bad.toml:3: key `body.ixx_kg_m2`"):
        helicon.Params.from_file(f)
    with pytest.raises(HeliconError, match="cannot read"):
        helicon.Params.from_file(tmp_path / "missing.toml")
    with pytest.raises(HeliconError, match="not valid TOML"):
        helicon.Params.from_toml("[body\n")


def test_model_with_edited_params_differs():
    x, u = hover_state()
    p = helicon.Params().replace({"body.mass_kg": 16.0})
    a = helicon.Model(params=p).derivative(x, u)
    b = helicon.Model().derivative(x, u)
    assert a[8] > b[8]  # heavier: accelerates down (w_dot > 0)
    assert helicon.Model(params=p).params == p
