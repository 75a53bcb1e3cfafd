"""The current sensor's lag nuisance (``current_lag``) against an exact oracle: a firmware's first-order filter
``i_f[n] = i_f[n-1] + alpha (i[n] - i_f[n-1])`` is undone exactly by ``i = i_f + lam (i_f[n] - i_f[n-1])``,
``lam = 1/alpha - 1`` samples, so ``lam`` times the nuisance's torque column must be exactly what the filter
leaves in each row's torque, ``k_t`` (filtered mean - true mean) of the current, also where the current steps."""

from __future__ import annotations

import numpy as np
from scipy import signal

from ocp.identify.columns import Signals, nuisance_columns, raw_signals
from ocp.logs import log_from_arrays
from ocp.model.params import MotorParams

P = MotorParams(J=1e-4, B=1e-5, c_tau=1e-7, c_f=1e-5, k_t=0.02, k_e=0.02, R=0.5, L=1e-4)
ALPHA = 0.62
DT = 0.005  # [s]


def _currents(n: int = 400) -> tuple[np.ndarray, np.ndarray]:
    """A true current (n,) [A] that steps every few samples (a fast armature under a stepped command) plus a slow
    part, and its firmware-filtered copy."""
    rng = np.random.default_rng(7)
    levels = np.repeat(rng.uniform(-5.0, 5.0, n // 5 + 1), 5)[:n]
    true = levels + np.sin(np.arange(n) * 0.05)
    filtered = signal.lfilter([ALPHA], [1.0, ALPHA - 1.0], true)  # i_f[n] = (1 - alpha) i_f[n-1] + alpha i[n]
    return true, filtered


def test_the_lag_column_undoes_the_filter_exactly_on_held_interval_rows() -> None:
    true, filt = _currents()
    n = true.size
    z = np.zeros(n - 1)
    s = Signals(z, z, filt[:-1], filt[1:], z, 0.5 * (filt[:-1] + filt[1:]), z, z, None, np.arange(n - 1) * DT, DT)
    col = nuisance_columns(P, s)["current_lag"][0]
    left = P.k_t * (0.5 * (filt[:-1] + filt[1:]) - 0.5 * (true[:-1] + true[1:]))  # what the filter leaves, (M,)
    lam = 1.0 / ALPHA - 1.0
    np.testing.assert_allclose(lam * col[1:], left[1:], rtol=1e-9, atol=1e-12)


def test_the_lag_column_undoes_the_filter_exactly_on_triangle_rows() -> None:
    true, filt = _currents()
    n = true.size
    t = np.arange(n) * DT
    theta = np.cumsum(np.full(n, 0.1))
    log = log_from_arrays(t, np.zeros(n), filt, np.zeros(n), omega=np.full(n, 20.0), theta=theta)
    s = raw_signals(log, theta)
    col = nuisance_columns(P, s)["current_lag"][0]
    tri = 0.25 * (np.concatenate([true[:1], true[:-2]]) + 2 * true[:-1] + true[1:])  # the rows' triangle means
    left = P.k_t * (s.i - tri)
    lam = 1.0 / ALPHA - 1.0
    np.testing.assert_allclose(lam * col[2:], left[2:], rtol=1e-9, atol=1e-12)
