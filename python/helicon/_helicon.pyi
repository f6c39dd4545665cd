"""Type stubs of the extension module ``helicon._helicon`` (PyO3).

The public API is the ``helicon`` package, which re-exports the classes
below and wraps the functions with defaults and docstrings.
"""

import os
from typing import Any, Dict, Iterator, List, Mapping, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

_Path = Union[str, os.PathLike[str]]
_Array = npt.ArrayLike

__version__: str
STATE_NAMES: Tuple[str, ...]
STATE_UNITS: Tuple[str, ...]
REDUCED_STATE_NAMES: Tuple[str, ...]
INPUT_NAMES: Tuple[str, ...]
LOG_COLUMNS: Tuple[str, ...]
LOG_UNITS: Tuple[str, ...]
METRIC_NAMES: Tuple[str, ...]

class HeliconError(ValueError):
    """An error of helicon, with the library's message (file, field, allowed range)."""

class Params:
    """The model parameters (SI units); ``Params()`` is the Bergen Industrial Twin.

    Keys are ``section.key`` as in the TOML files; edits are validated as a
    file is (each key's rule, then the cross-key rules) and leave the
    parameters unchanged on an error.
    """

    def __init__(self) -> None: ...
    @staticmethod
    def from_file(path: _Path) -> Params:
        """The Bergen Twin with a TOML file's keys overriding it, validated."""
    @staticmethod
    def from_toml(text: str, name: str = "<string>") -> Params:
        """The Bergen Twin with TOML text's keys overriding it; ``name`` labels errors."""
    def to_toml(self) -> str:
        """The complete set as a TOML file (as ``helicon params`` prints it)."""
    def to_dict(self) -> Dict[str, Any]:
        """Nested dicts as the TOML tables; counts are ints, switches bools."""
    @staticmethod
    def keys() -> List[str]:
        """Every key, ``section.key``, in file order."""
    @staticmethod
    def describe(key: str) -> Dict[str, str]:
        """``{"unit", "symbol", "rule"}`` of a key."""
    def replace(self, edits: Mapping[str, Any]) -> Params:
        """A validated copy with ``edits`` (dotted keys or nested dicts) applied."""
    def update(self, edits: Mapping[str, Any]) -> None:
        """Apply ``edits`` in place, all or none."""
    def copy(self) -> Params:
        """A copy."""
    def __getitem__(self, key: str) -> Union[float, int, bool]: ...
    def __setitem__(self, key: str, value: Union[float, int, bool]) -> None: ...
    def __contains__(self, key: object) -> bool: ...
    def __len__(self) -> int: ...
    def __iter__(self) -> Iterator[str]: ...
    def __eq__(self, other: object) -> bool: ...

class Model:
    """The nonlinear model ``ẋ = f(x, u, wind)`` (thesis chapters 4–10)."""

    def __init__(self, preset: str = "physical", params: Union[Params, _Path, None] = None) -> None: ...
    @property
    def preset(self) -> str:
        """``"physical"`` or ``"thesis"``."""
    @property
    def params(self) -> Params:
        """A copy of the parameters."""
    def derivative(self, x: _Array, u: _Array, wind: Optional[_Array] = None) -> np.ndarray:
        """ẋ for one state ``(30,)`` or a batch ``(N, 30)`` (same shape out).

        ``u`` is ``(4,)`` or ``(N, 4)``; ``wind`` (NED air-mass velocity, m/s)
        ``(3,)``, ``(N, 3)`` or None for still air. The batch runs with the
        GIL released, rows in parallel, each bit-identical to a single call.
        """

class Scenario:
    """A closed-loop scenario (TOML), validated."""

    @staticmethod
    def from_file(path: _Path) -> Scenario:
        """Load a scenario file (relative paths resolve against its folder)."""
    @staticmethod
    def from_toml(text: str, base_dir: Optional[_Path] = None, name: str = "<string>") -> Scenario:
        """A scenario from TOML text; ``base_dir`` resolves relative paths."""
    @property
    def name(self) -> str: ...
    @property
    def duration_s(self) -> float: ...
    @property
    def preset(self) -> str: ...
    @property
    def cases(self) -> List[str]:
        """The ``[[case]]`` labels (the scenario's name when it has none)."""
    def to_toml(self) -> str:
        """The effective scenario as TOML (without ``[[case]]`` entries)."""

def trim(
    preset: str,
    velocity_ned: _Array,
    params: Union[Params, _Path, None],
    yaw: float,
    wind_ned: Optional[_Array],
) -> Dict[str, Any]: ...
def linearize(
    preset: str,
    velocity_ned: _Array,
    params: Union[Params, _Path, None],
    yaw: float,
    wind_ned: Optional[_Array],
    thesis_inflow: bool,
    dt: Optional[float],
    allow_unphysical: bool,
) -> Tuple[np.ndarray, ...]: ...
def dare(a: _Array, b: _Array, q: _Array, r: _Array, n: Optional[_Array] = None) -> np.ndarray: ...
def dlqr(
    a: _Array, b: _Array, q: _Array, r: _Array, n: Optional[_Array] = None
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]: ...
def dlqe(
    a: _Array, g: Optional[_Array], c: _Array, qn: _Array, rn: _Array
) -> Tuple[np.ndarray, np.ndarray, np.ndarray]: ...
def kalman_filter(
    a: _Array, g: Optional[_Array], c: _Array, qn: _Array, rn: _Array
) -> Tuple[np.ndarray, np.ndarray]: ...
def c2d(a: _Array, b: _Array, dt: float) -> Tuple[np.ndarray, np.ndarray]: ...
def sim(
    scenario: Union[Scenario, str],
    duration: Optional[float],
    seed: Optional[int],
    params: Union[Params, str, None],
) -> List[Dict[str, Any]]: ...
def mc(
    campaign: str,
    runs: Optional[int],
    threads: Optional[int],
    seed: Optional[int],
    duration: Optional[float],
    params: Optional[str],
) -> Dict[str, Any]: ...
def frf(
    t: _Array,
    u: _Array,
    y: _Array,
    omega_min: Optional[float],
    omega_max: Optional[float],
    points: int,
    windows: int,
    conditioned_on: Optional[_Array],
    max_window_s: Optional[float],
) -> List[Dict[str, np.ndarray]]: ...
def ulog_read(path: _Path) -> Dict[str, Any]: ...
