"""helicon.control against SciPy and python-control on the same systems."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg
import scipy.signal

import helicon
from helicon import HeliconError, control

control_lib = pytest.importorskip("control")


def rel(a, b):
    return np.max(np.abs(a - b)) / max(np.max(np.abs(b)), 1e-300)


@pytest.fixture(scope="module")
def heli():
    """The Bergen Twin in hover at 400 Hz, and the thesis-like weights."""
    A, B, Phi, Gamma = helicon.linearize(dt=0.0025)
    Q = np.eye(27)
    R = 10.0 * np.eye(4)
    return A, B, Phi, Gamma, Q, R


def random_system(seed, n=6, m=2):
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n)) * 0.5
    B = rng.standard_normal((n, m))
    Q = np.diag(rng.uniform(0.1, 2.0, n))
    R = np.diag(rng.uniform(0.1, 2.0, m))
    return A, B, Q, R


def test_dare_equals_scipy_on_the_helicopter(heli):
    _, _, Phi, Gamma, Q, R = heli
    X = control.dare(Phi, Gamma, Q, R)
    ref = scipy.linalg.solve_discrete_are(Phi, Gamma, Q, R)
    assert rel(X, ref) < 1e-8


@pytest.mark.parametrize("seed", range(5))
def test_dare_equals_scipy_on_random_systems(seed):
    A, B, Q, R = random_system(seed)
    assert rel(control.dare(A, B, Q, R), scipy.linalg.solve_discrete_are(A, B, Q, R)) < 1e-10


def test_dare_with_cross_weight_equals_scipy():
    A, B, Q, R = random_system(9)
    N = 0.05 * np.ones((6, 2))
    ref = scipy.linalg.solve_discrete_are(A, B, Q, R, s=N)
    assert rel(control.dare(A, B, Q, R, N), ref) < 1e-10


def test_dlqr_equals_python_control(heli):
    _, _, Phi, Gamma, Q, R = heli
    K, X, E = control.dlqr(Phi, Gamma, Q, R)
    K2, X2, E2 = control_lib.dlqr(Phi, Gamma, Q, R)
    assert K.shape == (4, 27) and X.shape == (27, 27) and E.dtype == np.complex128
    assert rel(K, K2) < 1e-8 and rel(X, X2) < 1e-8
    assert np.allclose(np.sort_complex(E), np.sort_complex(E2), rtol=0, atol=1e-9)
    assert np.max(np.abs(E)) < 1.0


@pytest.mark.parametrize("seed", range(3))
def test_dlqr_equals_python_control_on_random_systems(seed):
    A, B, Q, R = random_system(seed)
    K, X, E = control.dlqr(A, B, Q, R)
    K2, X2, E2 = control_lib.dlqr(A, B, Q, R)
    assert rel(K, K2) < 1e-10 and rel(X, X2) < 1e-10


def test_dlqe_equals_python_control(heli):
    _, _, Phi, _, _, _ = heli
    C = np.hstack([np.eye(9), np.zeros((9, 18))])
    G = np.eye(27)
    QN = 1e-4 * np.eye(27)
    RN = 1e-3 * np.eye(9)
    L, P, E = control.dlqe(Phi, G, C, QN, RN)
    L2, P2, E2 = control_lib.dlqe(Phi, G, C, QN, RN)
    assert rel(L, L2) < 1e-7 and rel(P, P2) < 1e-7
    L3, P3, _ = control.kalman(Phi, C, QN, RN)  # G = identity
    assert np.array_equal(L3, L) and np.array_equal(P3, P)
    M, Z = control.kalman_filter(Phi, C, QN, RN)
    assert rel(Phi @ M, L) < 1e-10
    assert rel(Z, P - M @ C @ P) < 1e-8


def test_c2d_equals_scipy(heli):
    A, B, Phi, Gamma, _, _ = heli
    Phi2, Gamma2 = control.c2d(A, B, 0.0025)
    assert np.array_equal(Phi2, Phi) and np.array_equal(Gamma2, Gamma)  # helicon.linearize's ZOH
    ref = scipy.signal.cont2discrete((A, B, np.eye(27), np.zeros((27, 4))), 0.0025, method="zoh")
    assert rel(Phi2, ref[0]) < 1e-12 and rel(Gamma2, ref[1]) < 1e-10
    A, B, _, _ = random_system(3)
    P, G = control.c2d(A, B, 0.1)
    ref = scipy.signal.cont2discrete((A, B, np.eye(6), np.zeros((6, 2))), 0.1)
    assert rel(P, ref[0]) < 1e-13 and rel(G, ref[1]) < 1e-13


def test_scalars_are_one_by_one():
    X = control.dare(0.9, 1.0, 1.0, 1.0)
    assert X.shape == (1, 1)
    assert abs(X[0, 0] - scipy.linalg.solve_discrete_are([[0.9]], [[1.0]], [[1.0]], [[1.0]])[0, 0]) < 1e-13


@pytest.mark.parametrize(
    "args, message",
    [
        ((np.eye(2), np.ones((3, 1)), np.eye(2), np.eye(1)), "B"),
        ((np.eye(2), np.ones((2, 1)), np.eye(2), -np.eye(1)), "R"),
        ((np.eye(2) * np.nan, np.ones((2, 1)), np.eye(2), np.eye(1)), "not finite"),
        ((np.ones((2, 2, 2)), np.ones((2, 1)), np.eye(2), np.eye(1)), "2-D"),
        ((np.array([[2.0, 0.0], [0.0, 1.0]]), np.array([[1.0], [0.0]]) * 0 + np.array([[0.0], [1.0]]), np.eye(2), np.eye(1)), "stabiliz"),
    ],
)
def test_bad_problems_raise(args, message):
    with pytest.raises(HeliconError, match=message):
        control.dlqr(*args)


def test_bad_sample_time_raises():
    with pytest.raises(HeliconError):
        control.c2d(np.eye(2), np.ones((2, 1)), 0.0)
    with pytest.raises(HeliconError):
        control.c2d(np.eye(2), np.ones((2, 1)), float("nan"))
