"""How far an integrated angle lets the ripple's count be decided (session 36; ``max_tracked_periods``,
:func:`.angle.tracked_periods`, :func:`.explain.spectrum_peak`).

Without an angle column the angle is the speed integrated, and the speed's white noise makes it drift as a random
walk: a count ``n``'s phase by ``n^2`` times the angle's variance. The tracking follows the phase between knots a
drift variance apart, but knots are at least :data:`DRIFT_SPAN` apart and at most :data:`MAX_PIECES` pieces; beyond
the count whose phase drifts by :data:`DRIFT_VAR` between those knots, a true count's tracked fit predicts held-out
rows no better than a wrong one's. Oracle for the limit: a Monte-Carlo random walk, the speed integrated as
:func:`.columns.raw_signals` integrates it (trapezoids). Cases (tuning sets, not the reported 0..199): 23112, a
tachometer at 1 kHz with a 10-period ripple, best fit at 34 (the true count's held-out share 0.18, 0.999 given the
rig's own angle): now not decided, the rig's count among the rivals; 14194, a tachometer at 5 kHz with 53 periods
beyond the 49 tracked, whose peak stands out (0.87 against at most 0.37): still decided.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from bench.modelcheck import case_log
from clients.cli.answers import print_diagnosis
from ocp.identify import diagnose
from ocp.identify.angle import DRIFT_SPAN, DRIFT_VAR, MAX_PERIODS, MAX_PIECES, tracked_periods
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _increment_variance(sigma_w: float, dt: float, seconds: float, trials: int, rng: np.random.Generator) -> float:
    """Variance [rad^2] of the trapezoid-integrated angle's change over ``seconds`` of a speed with white noise
    ``sigma_w`` [rad/s] per sample of ``dt`` [s], over ``trials`` independent walks."""
    m = round(seconds / dt)
    w = sigma_w * rng.standard_normal((trials, m + 1))
    return float(np.var(np.sum(0.5 * (w[:, 1:] + w[:, :-1]) * dt, axis=1)))


@pytest.mark.parametrize("seconds", [0.6, 6.0, 40.0])  # one piece (the whole log), a knot a second, MAX_PIECES
def test_the_tracked_count_is_where_the_phase_walk_reaches_the_drift_variance(seconds: float) -> None:
    rng = np.random.default_rng(7)
    dt = 1e-3
    spacing = seconds / max(1, min(MAX_PIECES, int(seconds / DRIFT_SPAN)))
    sigma_w = math.sqrt(DRIFT_VAR / (10.5**2 * dt * spacing))  # the limit halfway between 10 and 11 periods
    t = np.arange(round(seconds / dt) + 1) * dt
    n = tracked_periods(t, sigma_w, dt)
    var = _increment_variance(sigma_w, dt, spacing, 4000, rng)  # the angle's walk between two knots, simulated
    assert n * n * var < DRIFT_VAR < (n + 1) ** 2 * var
    assert n == 10
    assert tracked_periods(t, 0.0, dt) == MAX_PERIODS  # a noiseless speed: every count followed


@pytest.mark.parametrize(("seed", "true", "decided"), [(23112, 10, False), (14194, 53, True)])
def test_a_count_beyond_the_tracking_is_decided_only_where_it_stands_out(
        seed: int, true: int, decided: bool, capsys: pytest.CaptureFixture[str]) -> None:
    case = make_case(seed)
    assert case.logger.speed == "tacho" and int(case.truth.effects["cogging"]["periods"]) == true
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    ap = res.angle_periodic
    assert "cogging" in res.verdict and ap is not None and ap["angle"] == "integrated"
    assert ap["max_tracked_periods"] < true  # both beyond what the tracking follows
    if decided:
        assert ap["periods"] == true and ap["rivals"] == []
    else:
        assert ap["periods"] != true and true in ap["rivals"]
        assert set(range(int(ap["max_tracked_periods"]) + 1, MAX_PERIODS + 1)) - {ap["periods"]} <= set(ap["rivals"])
    print_diagnosis(res.to_dict())
    out = capsys.readouterr().out
    assert ("the integrated angle drifts faster than a ripple's phase can be followed" in out) is not decided
    assert f"its phase is followed up to {ap['max_tracked_periods']} periods/rev only" in out
