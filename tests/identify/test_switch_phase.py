"""The drive's switching instant inside a held row, a nuisance of the model check's torque equation (issue #11).

A drive that applies a new command ``phi`` of a row after the sample (a PWM period's latch) makes the row's mean
armature current -- what eq. dc_mechanical's ``k_t i`` integrates -- differ from the mean of the sampled currents at
the row's ends. :func:`ocp.identify.columns.nuisance_columns` offers ``switch_phase``: ``x = phi - 1/2`` times
``-(2c - 1) k_t q`` with ``q = (i1 - i0) + (k_e/R)(w1 - w0)`` and ``c`` = :func:`.columns.settle_weight`; it is exact
for a switch at the row's start whatever the armature, and for any ``phi`` where the armature settles within the row.

Oracle: the armature ODE ``L i' = V(t) - R i - k_e w(t)`` integrated by scipy's adaptive Runge-Kutta to 1e-12 over a
row whose speed ramps linearly and whose drive switches from an old level to a new one at ``phi``.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp.identify.columns import Signals, nuisance_columns
from ocp.model.params import MotorParams

DT = 0.01  # [s] a 100 Hz logger
W0, W1 = 40.0, 55.0  # [rad/s] the speed at the row's ends
V_OLD, V_NEW = 3.0, 9.0  # [V]


def _row(p: MotorParams, phi: float, i0: float) -> tuple[float, float]:
    """(end current [A], mean current [A]) over one row from ``i0`` [A] (module doc)."""
    def rhs(t: float, y: np.ndarray) -> list[float]:
        v = V_OLD if t < phi * DT else V_NEW
        return [(v - p.R * y[0] - p.k_e * (W0 + (W1 - W0) * t / DT)) / p.L, y[0]]

    out = solve_ivp(rhs, (0.0, DT), [i0, 0.0], method="RK45", rtol=1e-12, atol=1e-14, max_step=DT / 2000,
                    first_step=DT / 1e6)
    return float(out.y[0, -1]), float(out.y[1, -1]) / DT


def _model(p: MotorParams, phi: float, i0: float, i1: float) -> float:
    """The row's mean current [A] as the torque equation models it: the end samples' mean plus the nuisance at
    ``x = phi - 1/2`` (its column is in torque: divided by ``-k_t``, the column's sign for a current)."""
    s = Signals(np.array([W0]), np.array([W1]), np.array([i0]), np.array([i1]), np.array([0.5 * (W0 + W1)]),
                np.array([0.5 * (i0 + i1)]), np.array([V_NEW]), np.zeros(1), None, np.zeros(1), DT)
    col = nuisance_columns(p, s)["switch_phase"][0, 0]
    return 0.5 * (i0 + i1) + (phi - 0.5) * col / p.k_t


@pytest.mark.parametrize("tau_samples", [0.002, 0.05, 0.3, 1.0, 3.0, 30.0])
def test_a_switch_at_the_row_start_is_exact_at_any_armature_speed(rig: MotorParams, tau_samples: float) -> None:
    p = rig.model_copy(update={"L": tau_samples * DT * rig.R})
    i0 = (V_OLD - p.k_e * W0) / p.R + 0.3  # (not settled: the relation does not assume it)
    i1, mean = _row(p, 0.0, i0)
    assert _model(p, 0.0, i0, i1) == pytest.approx(mean, rel=1e-7, abs=1e-9)


@pytest.mark.parametrize("phi", [0.0, 0.2, 0.5, 0.8])
def test_a_fast_armature_switched_inside_the_row(rig: MotorParams, phi: float) -> None:
    """L/R a thousandth of a row: the current follows the drive, so the row's mean is the old level for ``phi`` of
    it and the new one after; the end samples' mean alone is off by up to half the jump."""
    p = rig.model_copy(update={"L": 1e-3 * DT * rig.R})
    i0 = (V_OLD - p.k_e * W0) / p.R  # settled under the old level
    i1, mean = _row(p, phi, i0)
    jump = (V_NEW - V_OLD) / p.R  # [A]; the current settles within L/R, 1e-3 of a row
    assert _model(p, phi, i0, i1) == pytest.approx(mean, abs=2e-3 * jump)
    assert abs(0.5 * (i0 + i1) - mean) == pytest.approx(abs(0.5 - phi) * jump, abs=0.02 * jump)
