"""Frequency-response identification from time histories, as ``helicon ident frf``."""

from __future__ import annotations

from typing import Dict, List, Optional, Union

import numpy as np

from . import _helicon

__all__ = ["frf"]


def frf(
    t,
    u,
    y,
    omega_min: Optional[float] = None,
    omega_max: Optional[float] = None,
    *,
    points: int = 200,
    windows: int = 5,
    conditioned_on=None,
    max_window_s: Optional[float] = None,
) -> Union[Dict[str, np.ndarray], List[Dict[str, np.ndarray]]]:
    """The frequency response from input ``u`` to output(s) ``y``, sampled at times ``t``.

    The computation of ``helicon ident frf`` (CIFER-style): a uniform sample
    time (an irregular ``t`` is resampled linearly at its median step;
    backwards steps and gaps over 5 steps are refused), overlapped Hann
    windows of record/2, record/4, … (``windows`` of them, at least 32
    samples and enough averages each), the cross spectra on ``points``
    log-spaced frequencies, responses conditioned on the correlated inputs
    ``conditioned_on`` (other servos, closed loop), composited over the
    windows.

    Parameters
    ----------
    t:
        Times (s), 1-D, increasing.
    u:
        The input, 1-D, same length as ``t``.
    y:
        One output (1-D) or several as the columns of an ``(N, k)`` array.
    omega_min, omega_max:
        Frequency range in rad/s (defaults: two periods in the longest
        window; 0.4 × the Nyquist frequency).
    points:
        Frequency points, log spaced (2 … 10000).
    windows:
        Window lengths composited (1 … 8).
    conditioned_on:
        Other inputs (1-D, or the columns of an ``(N, q)`` array).
    max_window_s:
        Longest window used (s).

    Returns
    -------
    dict, or a list of dicts for a 2-D ``y``
        ``omega_rad_s``, ``mag_db``, ``phase_deg`` (unwrapped),
        ``coherence`` (γ², 0…1) and ``random_error`` (normalised ε of |H|),
        the columns of the CLI's ``frf.csv``.
    """
    many = np.ndim(y) == 2
    out = _helicon.frf(
        t,
        u,
        y,
        None if omega_min is None else float(omega_min),
        None if omega_max is None else float(omega_max),
        int(points),
        int(windows),
        conditioned_on,
        None if max_window_s is None else float(max_window_s),
    )
    return out if many else out[0]
