"""A load torque's columns are its means over each row, the speed linear within the row (columns._row_mean): a
friction's sign flips inside the row where the speed passes zero, and at the row's mean speed it was taken whole."""

from __future__ import annotations

import numpy as np

from ocp.identify.columns import ROW_POINTS, Signals, _effect, _row_mean
from ocp.model.params import MotorParams

P = MotorParams(J=2e-4, B=1e-5, c_tau=1e-6, c_f=1e-4, k_t=0.02, k_e=0.02, R=0.5, L=1e-4)


def _rows(w0: np.ndarray, w1: np.ndarray) -> Signals:
    z = np.zeros_like(w0)
    return Signals(w0, w1, z, z, 0.5 * (w0 + w1), z, z, z, None, z, 1e-3)


def test_a_sign_flipping_inside_a_row_is_its_mean() -> None:
    """Oracle, closed form: over a row whose speed goes linearly from ``w0`` to ``w1`` through zero, the mean of
    ``sign(w)`` is ``(|w1| - |w0|) / (w1 - w0)``; the midpoint rule's points resolve it to ``1 / ROW_POINTS``
    (a point on the wrong side of the flip moves the mean by ``2 / ROW_POINTS``; the rule's points are half a step
    in, so by at most half that)."""
    rng = np.random.default_rng(1)
    w0, w1 = -rng.uniform(0.1, 20.0, 200), rng.uniform(0.1, 20.0, 200)
    s = _rows(w0, w1)
    col = _effect("coulomb_friction", {"tau_c": 1.0, "omega_eps": 1e-3}, P, s)[0]
    exact = (np.abs(w1) - np.abs(w0)) / (w1 - w0)
    assert np.max(np.abs(col - exact)) <= 1.0 / ROW_POINTS + 1e-9
    # at the row's mean speed the sign was +-1 whole: off by up to 1 - |exact|
    at_mean = np.tanh(s.w / 1e-3)
    assert np.max(np.abs(at_mean - exact)) > 0.9


def test_a_smooth_load_is_the_exact_row_mean() -> None:
    """Oracle, closed form: the mean of ``w |w|`` over a linear path on one side of zero is
    ``(w1^3 - w0^3) / (3 (w1 - w0))``; the midpoint rule errs by ``(w1 - w0)^2 / (12 ROW_POINTS^2)`` for it."""
    w0, w1 = np.array([10.0, 40.0, -5.0]), np.array([30.0, 41.0, -25.0])
    got = _row_mean(lambda w: w * np.abs(w), _rows(w0, w1))
    exact = np.sign(w0) * (w1 ** 3 - w0 ** 3) / (3 * (w1 - w0))
    assert np.allclose(got, exact, rtol=0, atol=np.max((w1 - w0) ** 2) / (12 * ROW_POINTS ** 2) + 1e-9)
    # a sweep's rows (dt = 0) take the load at their speed
    sweep = Signals(w0, w0, w0, w0, w0, w0, w0, w0, None, w0, 0.0)
    assert np.array_equal(_row_mean(lambda w: w * np.abs(w), sweep), w0 * np.abs(w0))
