"""Linear time-invariant design: DARE, discrete LQR, steady-state Kalman gains, ZOH.

The functions of ``helicon-lti`` (the ones the toolkit designs its
controllers with), in python-control's conventions: ``u = -K x``,
``dlqr → (K, X, E)``, ``dlqe → (L, P, E)``. Matrices are 2-D array-likes
(a scalar is 1 × 1), converted to ``float64``; every entry must be finite.
Errors (shapes, definiteness, no stabilizing solution) are
:class:`helicon.HeliconError` naming the argument.

The DARE is solved by the structured doubling algorithm with a residual
check, not by an eigenvalue method: results agree with SciPy's
``solve_discrete_are`` and python-control to ~1e-12 relative on
well-conditioned problems (tests/test_control.py).
"""

from __future__ import annotations

from typing import Optional, Tuple

import numpy as np

from . import _helicon

__all__ = ["dare", "dlqr", "dlqe", "kalman", "kalman_filter", "c2d"]


def dare(A, B, Q, R, N=None) -> np.ndarray:
    """The stabilizing solution X of the discrete algebraic Riccati equation.

    ``X = AᵀXA − (AᵀXB + N)(R + BᵀXB)⁻¹(BᵀXA + Nᵀ) + Q`` with ``Q ⪰ 0``,
    ``R ≻ 0`` (and the joint weight ⪰ 0 when the cross weight ``N`` is
    given); the same X as ``scipy.linalg.solve_discrete_are(A, B, Q, R, s=N)``.
    """
    return _helicon.dare(A, B, Q, R, N)


def dlqr(A, B, Q, R, N=None) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Discrete LQR for ``x(k+1) = A x(k) + B u(k)``, as ``control.dlqr``.

    Minimizes ``Σ xᵀQx + uᵀRu + 2xᵀNu``. Returns ``(K, X, E)``: the gain of
    ``u = −K x`` (m × n), the Riccati solution X (n × n) and the closed-loop
    eigenvalues ``eig(A − BK)`` (complex, sorted by real part).
    """
    return _helicon.dlqr(A, B, Q, R, N)


def dlqe(A, G, C, QN, RN) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Steady-state Kalman predictor gain, as ``control.dlqe(A, G, C, QN, RN)``.

    For ``x(k+1) = A x + B u + G w``, ``y = C x + v`` with ``E[wwᵀ] = QN``,
    ``E[vvᵀ] = RN``. ``G=None`` means the identity (then QN is n × n).
    Returns ``(L, P, E)``: the predictor gain
    ``L = A P Cᵀ (C P Cᵀ + RN)⁻¹`` of ``x̂(k+1) = A x̂ + B u + L (y − C x̂)``,
    the prior error covariance P and the estimator poles ``eig(A − LC)``.
    """
    return _helicon.dlqe(A, G, C, QN, RN)


def kalman(A, C, Qn, Rn, G=None) -> Tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The steady-state Kalman gain: :func:`dlqe` with the noise input ``G`` last (optional).

    Returns ``(L, P, E)`` as :func:`dlqe`.
    """
    return _helicon.dlqe(A, G, C, Qn, Rn)


def kalman_filter(A, C, Qn, Rn, G=None) -> Tuple[np.ndarray, np.ndarray]:
    """The steady-state Kalman *filter* (current-estimator) gain.

    Returns ``(M, Z)``: ``M = P Cᵀ (C P Cᵀ + Rn)⁻¹`` of
    ``x̂(k|k) = x̄(k) + M (y(k) − C x̄(k))`` (so that ``L = A M``) and the
    posterior error covariance ``Z = P − M C P``.
    """
    return _helicon.kalman_filter(A, G, C, Qn, Rn)


def c2d(A, B, dt: float) -> Tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretization ``(Phi, Gamma)`` at sample time ``dt`` (s, > 0).

    ``Phi = e^{A dt}``, ``Gamma = ∫₀^dt e^{A s} ds B`` (scaling and squaring
    matrix exponential), as ``scipy.signal.cont2discrete((A, B, C, D), dt)``.
    """
    return _helicon.c2d(A, B, float(dt))
