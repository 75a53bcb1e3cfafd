"""A fraction of a sample of command lag is a drive switching within the row (issue #11, session 24).

The alignment measures the lag to a fraction of a sample, and the equations see the command moved by it
(:func:`ocp.identify.align.realign`). Interpolating the fraction blends the old and the new level over the row: right
for an armature much slower than a row (its current integrates both), wrong for one that settles within it (its
current shows only the new level at the next sample). On clean proving-ground logs at L/R of half a sample the blend
was taken for an inductance 42-45 % low. :func:`ocp.identify.align.switched` gives the lag whose interpolation drives
the nominal armature over each row as the switch does.

Oracle: the armature ODE ``L i' = V(t) - R i - k_e w`` integrated by scipy's adaptive Runge-Kutta to 1e-12 over a row
whose drive switches from the old level to the new one ``f`` of a row late.
"""

from __future__ import annotations

import math
import sys

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp.identify import align as align_mod
from ocp.identify.align import shifted, switched
from ocp.identify.inductance import TIMING_MIMICS
from ocp.model.params import MotorParams

DT = 0.002  # [s] a 500 Hz logger
W = 50.0  # [rad/s] a steady speed
V_OLD, V_NEW = 3.0, 9.0  # [V]


def _end_current(p: MotorParams, f: float, i0: float) -> float:
    def rhs(t: float, y: np.ndarray) -> list[float]:
        return [((V_OLD if t < f * DT else V_NEW) - p.R * y[0] - p.k_e * W) / p.L]

    out = solve_ivp(rhs, (0.0, DT), [i0], method="RK45", rtol=1e-12, atol=1e-14, max_step=DT / 2000,
                    first_step=DT / 1e6)
    return float(out.y[0, -1])


@pytest.mark.parametrize("tau", [0.05, 0.5, 2.0, 20.0])
@pytest.mark.parametrize("lag", [0.2, 1.7])
def test_the_realigned_row_drives_the_armature_as_the_switch_does(rig: MotorParams, tau: float, lag: float) -> None:
    """The command logged a step earlier, moved by ``switched(lag, tau)``: the held row's voltage through the exact
    zero-order-hold step (eq. dc_electrical) gives the end current of the drive that switched ``lag`` mod 1 of the row
    late."""
    p = rig.model_copy(update={"L": tau * DT * rig.R})
    m, f = math.floor(lag), lag - math.floor(lag)
    logged = np.array([V_OLD] * 4 + [V_NEW] * 4)  # the new command logged at row 4, applied from row 4 + lag
    row = 4 + m  # the row the drive switches in
    v = shifted(logged, switched(lag, tau))[row]
    i0 = (V_OLD - p.k_e * W) / p.R + 0.1
    a = math.exp(-DT * p.R / p.L)
    zoh = a * i0 + (1.0 - a) * (v - p.k_e * W) / p.R
    assert zoh == pytest.approx(_end_current(p, f, i0), rel=1e-7, abs=1e-9)


def test_limits_interpolation_for_a_slow_armature_whole_samples_for_a_fast_one() -> None:
    assert switched(2.3, 1e6) == pytest.approx(2.3, abs=1e-5)
    assert switched(2.3, 1e-3) == pytest.approx(2.0, abs=1e-9)
    assert switched(3.0, 0.5) == pytest.approx(3.0)
    assert 2.0 < switched(2.3, 0.5) < 2.3


@pytest.mark.parametrize("seed", [6060, 9105])
def test_clean_fast_armatures_name_no_inductance(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """Proving-ground seeds 6060 and 9105 (500 Hz encoders, L/R 0.49 and 0.57 samples, clean; validation sets, found
    in session 24): nothing named; with the fraction interpolated (the realignment before) ``L`` is fitted 42-45 %
    low, which since session 33 the timing that mimics it predicts as well (:func:`.inductance.inductance_wins`),
    and without that judge it is named (the test can fail)."""
    from bench.modelcheck import case_log
    from ocp.identify import diagnose
    from ocp.model.plant import DCMotorPlant
    from tests.proving_ground import make_case

    case = make_case(seed)
    plant = DCMotorPlant(MotorParams(**case.nominal))
    assert not case.expected
    assert diagnose(plant, case_log(case)).verdict == []
    for module in (align_mod, sys.modules["ocp.identify.diagnose"]):
        monkeypatch.setattr(module, "switched", lambda samples, tau: samples)
    res = diagnose(plant, case_log(case))
    assert res.verdict == [] and res.calibration["L"]["unresolved"] == TIMING_MIMICS
    monkeypatch.setattr(sys.modules["ocp.identify.diagnose"], "inductance_wins", lambda *args: True)
    assert diagnose(plant, case_log(case)).verdict == ["param:L"]
