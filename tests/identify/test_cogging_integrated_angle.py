"""Angle-periodic torque on a log without an angle column: the angle integrated from a tachometer drifts (a random
walk of the speed noise), so the ripple's phase is tracked through overlapping windows, and its period count is
looked for where the torque equation is judged (the speed view), not in the differentiated speed's noise."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify import diagnose
from ocp.identify.angle import MAX_WINDOWS, PHASE_DRIFT, drift_time, phase_windows, tracking_windows
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def test_drift_time_is_where_the_random_walk_reaches_the_phase_budget() -> None:
    """``n sigma_w sqrt(dt T) = PHASE_DRIFT`` at T = drift_time; twice the periods, a quarter of the time."""
    t = drift_time(2.0, 1e-3, 10)
    assert 10 * 2.0 * math.sqrt(1e-3 * t) == pytest.approx(PHASE_DRIFT)
    assert drift_time(2.0, 1e-3, 20) == pytest.approx(t / 4)
    assert drift_time(0.0, 1e-3, 10) == math.inf


def test_windows_sum_to_one_and_follow_the_spacing() -> None:
    t = np.linspace(0.0, 6.0, 6001)
    w = phase_windows(t, 1.0)
    assert w.shape == (7, t.size)
    assert np.allclose(w.sum(axis=0), 1.0) and w.min() >= 0.0
    assert phase_windows(t, 10.0).shape == (1, t.size)  # the spacing covers the log: one window
    assert tracking_windows(t, 5.0, 1e-3, 40, logged=True).shape == (1, t.size)  # an encoder angle does not drift
    assert tracking_windows(t, 5.0, 1e-3, 40, logged=False).shape[0] == 7  # drift time 0.8 ms: 1 s apart at least
    long = np.linspace(0.0, 30.0, 3001)
    assert tracking_windows(long, 5.0, 1e-3, 40, logged=False).shape[0] == MAX_WINDOWS  # and at most so many


def test_a_ripple_against_an_integrated_angle_is_named() -> None:
    """Proving-ground draw 1182 (a tuning seed: 200 Hz tachometer log of 17.6 s, chirp and ramp): a 3-period ripple
    of 88 mN m whose integrated angle drifts by 1.8 rad (5.4 rad of ripple phase) over the log. The code before
    this test found 4 periods in the differentiated speed's noise and named nothing."""
    case = make_case(1182)
    assert case.expected == {"cogging"} and case.logger.speed == "tacho"
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"])
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert res.verdict == ["cogging"]
    assert res.angle_periodic is not None and res.angle_periodic["periods"] == 3
    assert res.angle_periodic["angle"] == "integrated"
