"""helicon in Python: the miniature-helicopter toolkit with NumPy in and out.

The nonlinear model of the Aalborg 2006 thesis *Nonlinear Modeling and
Optimal Control of a Miniature Autonomous Helicopter* (the Bergen Industrial
Twin), its trim and linearization anywhere in the envelope, LQR and Kalman
design, closed-loop flights and Monte Carlo campaigns, frequency-response
identification and flight-log reading — the same code as the ``helicon``
command line, called in-process.

Conventions: SI units (m, s, rad, m/s, rad/s, N); NED earth frame, FRD body
frame; NumPy ``float64`` arrays in and out; the state and input orders of
:func:`state_names` and :func:`input_names`. Every error is a
:class:`HeliconError` (a ``ValueError``) carrying the library's message,
which names the file, the field and the allowed range.

>>> import helicon
>>> t = helicon.trim(velocity_ned=(8.0, 0.0, 0.0))
>>> A, B = helicon.linearize(velocity_ned=(8.0, 0.0, 0.0))
>>> A.shape, B.shape
((27, 27), (27, 4))

Submodules: :mod:`helicon.control` (dare, dlqr, dlqe/kalman, c2d),
:mod:`helicon.ident` (frf), :mod:`helicon.ulog` (read).
"""

from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np

from . import _helicon
from ._helicon import HeliconError, Model, Params, Scenario

__version__: str = _helicon.__version__

__all__ = [
    "__version__",
    "HeliconError",
    "Params",
    "Model",
    "Scenario",
    "state_names",
    "state_units",
    "reduced_state_names",
    "input_names",
    "log_columns",
    "log_units",
    "trim",
    "linearize",
    "sim",
    "SimResult",
    "mc",
    "McResult",
    "control",
    "ident",
    "ulog",
]

PathLike = Union[str, "os.PathLike[str]"]
Vector3 = Union[Sequence[float], np.ndarray]


def state_names() -> List[str]:
    """The 30 state names, in the order of every state array.

    ``x y z`` (NED position, m), ``phi theta psi`` (3-2-1 Euler angles,
    rad), ``u v w`` (body velocity, m/s), ``p q r`` (body rates, rad/s),
    main-rotor flapping ``a0 a1 b1`` and rates, stabilizer-bar flapping
    ``a1sb b1sb`` and rates, the servo angles ``theta0 A1 B1 theta_tr`` (rad)
    and their rates (docs/model.md).
    """
    return list(_helicon.STATE_NAMES)


def state_units() -> List[str]:
    """The SI unit of each of the 30 states, in :func:`state_names` order."""
    return list(_helicon.STATE_UNITS)


def reduced_state_names() -> List[str]:
    """The 27 states of trim and linearization: :func:`state_names` without ``x y z``.

    The rows and columns of ``A`` and the rows of ``B`` from
    :func:`linearize` are in this order.
    """
    return list(_helicon.REDUCED_STATE_NAMES)


def input_names() -> List[str]:
    """The 4 inputs ``S_col S_lat S_lon S_tr`` (dimensionless servo commands)."""
    return list(_helicon.INPUT_NAMES)


def log_columns() -> List[str]:
    """The columns of a flight log (``log.csv``), in order: the keys of :attr:`SimResult.log`."""
    return list(_helicon.LOG_COLUMNS)


def log_units() -> Dict[str, str]:
    """The SI unit of each flight-log column (``"1"`` for dimensionless)."""
    return dict(zip(_helicon.LOG_COLUMNS, _helicon.LOG_UNITS))


def _count(name: str, value: Optional[int]) -> Optional[int]:
    """An optional whole number >= 0 (seeds, runs, threads), or HeliconError."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise HeliconError(f"{name} = {value!r}: must be a whole number")
    if value < 0 or value >= 2**64:
        raise HeliconError(f"{name} = {value}: must be within 0 .. 2^64 - 1")
    return int(value)


def _fspath(value: Any) -> Any:
    """A path-like as str; anything else unchanged (the module names what it expected)."""
    return os.fspath(value) if isinstance(value, (str, os.PathLike)) else value


def _heading(yaw: float, yaw_rate: float) -> float:
    if yaw_rate != 0.0:
        raise HeliconError(
            f"yaw_rate = {yaw_rate} rad/s: the trim solves steady straight flight "
            "(constant velocity and heading), so only yaw_rate = 0 is available; "
            "give the heading with yaw="
        )
    return float(yaw)


def trim(
    preset: str = "physical",
    velocity_ned: Vector3 = (0.0, 0.0, 0.0),
    params: Union[Params, PathLike, None] = None,
    yaw_rate: float = 0.0,
    *,
    yaw: float = 0.0,
    wind_ned: Optional[Vector3] = None,
) -> Dict[str, Any]:
    """Trim the helicopter in steady straight flight, as ``helicon trim --json``.

    Parameters
    ----------
    preset:
        ``"physical"`` (the printed equations, physical conventions) or
        ``"thesis"`` (what the thesis implementation computed).
    velocity_ned:
        Inertial velocity ``(vn, ve, vd)`` in m/s (each within ±100 m/s).
    params:
        A :class:`Params`, a parameter TOML file, or ``None`` for the Bergen Twin.
    yaw_rate:
        Must be 0 (rad/s): the trim is of straight flight.
    yaw:
        Heading ψ in rad (within ±100 rad).
    wind_ned:
        Air-mass velocity ``(n, e, d)`` in m/s (where the air moves to).

    Returns
    -------
    dict
        ``"state"`` (27 reduced states by name), ``"input"`` (4 by name),
        ``"lambda_mr"``, ``"lambda_tr"``, ``"residual_norm"``,
        ``"iterations"``, ``"velocity_ned_m_s"``, ``"yaw_rad"``,
        ``"wind_ned_m_s"``, ``"beyond_saturation"`` and ``"validity"``
        (``{"physical": bool, "violations": [...]}``, each violation with its
        quantity, value, allowed range and reason). An unphysical trim is
        returned, not raised: check ``result["validity"]["physical"]``.

    Raises
    ------
    HeliconError
        Out-of-range arguments, invalid parameters, or no convergence.
    """
    return _helicon.trim(preset, velocity_ned, params, _heading(yaw, yaw_rate), wind_ned)


def linearize(
    preset: str = "physical",
    velocity_ned: Vector3 = (0.0, 0.0, 0.0),
    params: Union[Params, PathLike, None] = None,
    thesis_inflow: bool = False,
    dt: Optional[float] = None,
    *,
    yaw: float = 0.0,
    wind_ned: Optional[Vector3] = None,
    allow_unphysical: bool = False,
) -> Union[Tuple[np.ndarray, np.ndarray], Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """Linearize at the trim of a flight condition, as ``helicon linearize``.

    Trims as :func:`trim`, then returns the continuous ``(A, B)`` of
    ``ẋ = A δx + B δu`` over the 27 reduced states (:func:`reduced_state_names`)
    and 4 inputs — the matrices of the CLI's ``A.csv`` and ``B.csv`` — and,
    with ``dt``, also their zero-order-hold discretization
    ``(A, B, Phi, Gamma)`` at that sample time (the CLI's ``--discrete``).

    Parameters
    ----------
    thesis_inflow:
        Emulate the thesis implementation's inflow (flapping on the trim λ,
        7 Newton–Raphson steps), reproducing the thesis's Appendix E.
    dt:
        Sample time in s (finite, > 0) for ``Phi, Gamma``.
    allow_unphysical:
        Linearize even when the trim is outside the physical ranges or the
        operating point is not an equilibrium (otherwise refused, as the CLI
        refuses without ``--allow-unphysical``).

    Raises
    ------
    HeliconError
        As :func:`trim`, and the refusals above.
    """
    return _helicon.linearize(
        preset,
        velocity_ned,
        params,
        float(yaw),
        wind_ned,
        bool(thesis_inflow),
        None if dt is None else float(dt),
        bool(allow_unphysical),
    )


class SimResult:
    """One flown case of a scenario.

    Attributes
    ----------
    name:
        The case's scenario name (``<scenario>-<case>`` for a ``[[case]]``).
    label:
        The case label (the ``[[case]]`` name, or the scenario name).
    log:
        The flight log: a dict of 1-D ``float64`` arrays keyed by the
        ``log.csv`` column names (:func:`log_columns`, units in
        :func:`log_units`), every ``[log] decimation``-th controller sample —
        the values ``helicon sim`` writes to ``log.csv``, bit for bit.
    summary:
        The ``summary.json`` content (outcome, termination, metrics per
        output, control effort, seeds, design figures).
    outcome:
        ``"completed"`` or ``"diverged"`` (a divergence is a result, not an error).
    """

    __slots__ = ("name", "label", "log", "summary", "outcome")

    def __init__(self, raw: Dict[str, Any]) -> None:
        self.name: str = raw["name"]
        self.label: str = raw["label"]
        self.log: Dict[str, np.ndarray] = raw["log"]
        self.summary: Dict[str, Any] = raw["summary"]
        self.outcome: str = raw["outcome"]

    @property
    def t_s(self) -> np.ndarray:
        """Time of each log row (s)."""
        return self.log["t_s"]

    def to_pandas(self) -> "Any":
        """The log as a ``pandas.DataFrame`` (needs pandas), one column per log column."""
        try:
            import pandas
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("SimResult.to_pandas() needs pandas: pip install pandas") from e
        return pandas.DataFrame(self.log)

    def __repr__(self) -> str:
        rows = len(self.log["t_s"]) if "t_s" in self.log else 0
        return (
            f"<helicon.SimResult {self.name!r}: {self.outcome}, "
            f"t_end = {self.summary.get('t_end_s')} s, {rows} log rows>"
        )


def sim(
    scenario: Union[Scenario, PathLike],
    duration: Optional[float] = None,
    seed: Optional[int] = None,
    params: Union[Params, PathLike, None] = None,
) -> List[SimResult]:
    """Fly a closed-loop scenario, as ``helicon sim`` (in memory, no files).

    Trims and linearizes at the scenario's design point, designs the LQR and
    Kalman gains (or loads its gains file), and flies the nonlinear model in
    closed loop with its wind and sensors.

    Parameters
    ----------
    scenario:
        A :class:`Scenario` or a scenario TOML file (docs/closed-loop.md).
    duration:
        Flight time in s instead of the scenario's ``duration_s`` (``--duration``).
    seed:
        Seed of both the wind and sensor random streams (``--seed``).
    params:
        Plant parameters instead of the scenario's ``params``: a
        :class:`Params` or a parameter TOML file (``--params``).

    Returns
    -------
    list of SimResult
        One per ``[[case]]`` of the scenario (one when it has none).

    Ctrl-C stops the flight being flown at its next controller sample and raises
    ``KeyboardInterrupt``.
    """
    raw = _helicon.sim(
        _fspath(scenario),
        None if duration is None else float(duration),
        _count("seed", seed),
        _fspath(params),
    )
    return [SimResult(r) for r in raw]


class McResult:
    """A flown Monte Carlo campaign (the content of ``runs.csv``, ``traces.csv``, ``stats.json``).

    Attributes
    ----------
    name:
        The campaign's name.
    dispersed:
        The dispersed parameter keys, in file order.
    runs:
        One entry per run, by index, as the columns of ``runs.csv``: ``index``
        (int64), ``wind_seed``, ``sensor_seed`` (uint64), each dispersed key
        (float64), ``outcome``, ``termination``, ``reason`` (lists of str),
        ``t_end_s`` and the metrics (float64, NaN where a metric is empty).
    traces:
        Per run, a ``(k, 5)`` array of ``t_s, vn, ve, vd, psi`` at the
        campaign's ``trace_rate_hz``.
    stats:
        The ``stats.json`` content (p5/p50/p95 of each metric over completed
        runs, failures by typed class).
    """

    __slots__ = ("name", "dispersed", "runs", "traces", "stats")

    def __init__(self, raw: Dict[str, Any]) -> None:
        self.name: str = raw["name"]
        self.dispersed: List[str] = raw["dispersed"]
        self.runs: Dict[str, Any] = raw["columns"]
        self.traces: List[np.ndarray] = raw["traces"]
        self.stats: Dict[str, Any] = raw["stats"]

    def __len__(self) -> int:
        return len(self.runs["index"])

    @property
    def records(self) -> List[Dict[str, Any]]:
        """The runs as one dict per run (a row of ``runs.csv``)."""
        keys = list(self.runs)
        return [
            {k: (v[i].item() if isinstance(v, np.ndarray) else v[i]) for k, v in ((k, self.runs[k]) for k in keys)}
            for i in range(len(self))
        ]

    def to_pandas(self) -> "Any":
        """The runs as a ``pandas.DataFrame`` (needs pandas), indexed by run."""
        try:
            import pandas
        except ImportError as e:  # pragma: no cover - depends on the environment
            raise ImportError("McResult.to_pandas() needs pandas: pip install pandas") from e
        return pandas.DataFrame(self.runs).set_index("index")

    def __repr__(self) -> str:
        return (
            f"<helicon.McResult {self.name!r}: {len(self)} runs, "
            f"{self.stats.get('completed')} completed, {self.stats.get('failed')} failed>"
        )


def mc(
    campaign: PathLike,
    runs: Optional[int] = None,
    threads: Optional[int] = None,
    *,
    seed: Optional[int] = None,
    duration: Optional[float] = None,
    params: Optional[PathLike] = None,
) -> McResult:
    """Fly a Monte Carlo campaign, as ``helicon mc`` (in memory, no files).

    Each run draws its dispersed parameters and seeds from its own stream, so
    a run's record depends only on the campaign and its index — the same
    whatever ``threads``, and the same as the CLI's ``runs.csv`` row.

    Parameters
    ----------
    campaign:
        A campaign TOML file (docs/monte-carlo.md).
    runs:
        Runs ``0..runs`` instead of the file's ``runs`` (≥ 1).
    threads:
        Worker threads (≥ 1; default one per core).
    seed, duration, params:
        The CLI's ``--seed``, ``--duration``, ``--params`` overrides.

    Ctrl-C stops the campaign between runs (raising ``KeyboardInterrupt``
    once the runs in flight have finished).
    """
    return McResult(
        _helicon.mc(
            _fspath(campaign),
            _count("runs", runs),
            _count("threads", threads),
            _count("seed", seed),
            None if duration is None else float(duration),
            _fspath(params),
        )
    )


from . import control, ident, ulog  # noqa: E402  (submodules use the names above)
