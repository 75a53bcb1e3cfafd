"""A named inductance error must predict better than the command timing that mimics it (issue #11, session 33).

In eq. dc_electrical an inductance error ``x`` leaves ``x L i'``, a command lag of ``d`` samples ``-d dt R i'``: on a
smooth command the circuit with ``L (1 + x)`` is the nominal one with the command ``x L/R`` later. The alignment's
search carries the sensors' noise, and a lag found a sample off was named an ``L`` error of ``1 / (L/R)`` samples
(proving ground, sessions 28-32: 11 false ``L`` over 800 logs, on clean ones too). ``L`` is now named only where the
plant with it predicts the held-out speed and current better (free run, by the selection's materiality) than the
nominal ``L`` under the best command timing the conventions explain, the other constants as calibrated beside ``L``
or nominal (:func:`ocp.identify.inductance.inductance_wins`; session 69: before, only the timing that mimics
``x`` and the constants nominal). Proving-ground draws from session 33's and 68's runs (not the reported seeds
0..199).
"""

from __future__ import annotations

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.identify.inductance import TIMING_MIMICS, TIMING_STEP, timings
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _rl_current(v: np.ndarray, dt: float, r: float, ell: float) -> np.ndarray:
    """Exact zero-order-hold response of ``L i' + R i = v`` (i(0) = 0) [A], ``v`` (N,) [V] held over ``dt`` [s]."""
    a = np.exp(-dt * r / ell)
    i = np.zeros(v.size)
    for k in range(1, v.size):
        i[k] = a * i[k - 1] + (1.0 - a) * v[k - 1] / r
    return i


def test_an_inductance_error_is_the_command_moved_by_x_l_over_r() -> None:
    """Oracle: the RL circuit integrated exactly. Under a smooth command the circuit with a 30 % larger L is best
    matched by the nominal circuit under the command ``0.3 L/R`` later (a grid of lags), which leaves a tenth of
    the mismatch (the rest is the larger L's amplitude roll-off, second order in ``w L/R``)."""
    dt, r, ell, x = 1e-4, 1.0, 3e-4, 0.3  # L/R = 3 samples
    t = np.arange(4000) * dt
    v = np.sin(2 * np.pi * 20 * t) + 0.5 * np.sin(2 * np.pi * 47 * t + 1.0)
    big = _rl_current(v, dt, r, ell * (1 + x))[500:]
    lags = np.arange(0.0, 2.0, 0.01)  # samples
    miss = [np.std(big - _rl_current(np.interp(t - d * dt, t, v, left=0.0), dt, r, ell)[500:]) for d in lags]
    assert abs(lags[int(np.argmin(miss))] - x * ell / r / dt) < 0.05
    assert min(miss) < 0.1 * miss[0]


@pytest.mark.parametrize(("seed", "reason"), [
    (23172, "L would have to be off by more than a factor two: a timing error"),
    pytest.param(23180, TIMING_MIMICS, marks=pytest.mark.xfail(strict=True, reason=(
        "session 60's alignment (the lag read from the nearest whole sample): 0.52 samples for 0.15 is applied as 0.57 "
        "where it was 0.47, and L -18 % is named; one of the ten sets' six broken logs (docs/model-check-rules.md)")))])
def test_a_lag_error_is_not_named_an_inductance_error(seed: int, reason: str) -> None:
    """2 kHz and 5 kHz encoder logs whose inductance is right: the lag found 2.22 samples for a drawn 1.13 (L/R
    2.36) and 0.52 for 0.15 (L/R 2.51) had named L -49 % and -14 %. The timing the L error mimics predicts as well
    (:data:`TIMING_MIMICS`); since session 60 23172's lag (2.28) leaves L -52 %, past the factor-two box, which the
    same timing explains."""
    case = make_case(seed)
    assert "param:L" not in case.expected and not case.constant_error
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert sorted(res.verdict) == sorted(case.expected)
    assert res.calibration["L"]["unresolved"].startswith(reason) and not res.calibration["L"]["named"]
    assert res.plant.params.L == pytest.approx(case.nominal["L"])  # the calibrated plant keeps nominal L


def test_an_inductance_error_that_predicts_better_stays_named() -> None:
    """6131: L 35 % low at an L/R of 5.85 samples, the lag measured within 0.25 samples: named, near the rig's."""
    case = make_case(6131)
    assert set(case.constant_error) == {"L"}
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert res.verdict == ["param:L"]
    assert abs(res.plant.params.L / case.truth.L - 1.0) < 0.15


def test_the_rival_timings_cover_the_conventions_and_the_mimicking_lag() -> None:
    """The grid spans the conventions ``0..top`` at :data:`TIMING_STEP`; the mimicking lag joins it only within."""
    assert timings(1.3, 2.75) == sorted([*np.arange(0.0, 2.76, TIMING_STEP).tolist(), 1.3])
    assert timings(-0.2, 2.75) == timings(3.1, 2.75) == np.arange(0.0, 2.76, TIMING_STEP).tolist()


@pytest.mark.parametrize(("seed", "kind"), [(3034, "clean"), (3099, "clean"), (3450, "one"), (3519, "one")])
def test_an_inductance_error_a_conventional_timing_explains_is_not_named(seed: int, kind: str) -> None:
    """Logs whose inductance is right (session 68's ten sets), each held back by one of the rival's two forms alone.
    Beside the timing with the other constants as calibrated (a lag on the grid predicts within the materiality where
    the mimicking one did not): 3034 (5 kHz chirp, L/R 0.66 samples, the lag found 0 for 0.28, ``L`` +79 %), 3519
    (1 kHz, found 2.07 for 2.29, ``L`` +55 %), 3450 (10 kHz PRBS, found 0.74 for 0.06, ``L`` -34 %, which its free
    run does not see; the mimicking lag lies just below 0, outside the conventions, and was not tried). Beside it
    with them nominal: 3099 (1 kHz, found 2.75 for 2.13, ``L`` -45 %), where the constants calibrated beside that
    ``L`` predict far worse (15.8 against 9.98 noise units at the mimicking lag)."""
    case = make_case(seed, kind)
    assert "param:L" not in case.expected and "L" not in case.constant_error
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert sorted(res.verdict) == sorted(case.expected)
    assert res.calibration["L"]["unresolved"] == TIMING_MIMICS and not res.calibration["L"]["named"]
    assert res.plant.params.L == pytest.approx(case.nominal["L"])
