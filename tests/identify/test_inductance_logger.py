"""The inductance against the logger's current filter and command timing (issue #11, session 11).

A first-order current filter of time constant ``t_f`` makes the armature equation see ``L + R t_f``: it only RAISES
the apparent inductance. What lowers it is a command timing error the alignment left. Two proving-ground draws
constructed for this test (``make_case(seed, kind="clean")``, seeds >= 3000, never the reported nor the tuning
seeds), a wrong constant made by telling ``diagnose`` a wrong nominal (as the proving ground does: true =
nominal (1 + e)):

* 3090: a clean 10 kHz log, L/R = 4.3 samples, the current filtered over 0.59 samples (apparent L 13.6 % high). The
  former code named ``param:L`` on it; the torque equation's current lag now widens L's box above nominal.
* 3094: a 2 kHz log, true L/R = 1.06 samples, a sharp alignment. Told L 40 % too high (true = 0.6 nominal, nominal
  L/R 1.8 samples), the former code left L unresolved (L/R under two samples); an apparent L that far BELOW
  nominal is no filter's, and is named.
"""

from __future__ import annotations

import functools

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.identify.align import LAG_STEP, Alignment, spread
from ocp.identify.inductance import FILTER_MIMICS
from ocp.logs import Log
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


@functools.cache
def _clean(seed: int) -> tuple[Log, dict[str, float], float, float]:
    """The clean draw's log, its (true) constants, the current filter [samples] and L/R [samples]."""
    case = make_case(seed, kind="clean")
    lg, p = case.logger, case.nominal
    return case_log(case), dict(p), (1.0 - lg.alpha) / lg.alpha, p["L"] / p["R"] / lg.dt


def _told(seed: int, l_error: float) -> tuple[Log, MotorParams]:
    """The log of ``seed`` and the nominal constants with ``L`` off by ``l_error`` (true = nominal (1 + e))."""
    log, nominal, _, _ = _clean(seed)
    return log, MotorParams(**{**nominal, "L": nominal["L"] / (1.0 + l_error)})


def test_current_filter_is_not_an_inductance_error() -> None:
    log, p = _told(3090, 0.0)
    _, _, filt, l_over_r = _clean(3090)
    assert filt == pytest.approx(0.59, abs=0.02) and l_over_r == pytest.approx(4.34, abs=0.05)
    res = diagnose(DCMotorPlant(p), log)
    # the filter shows as an inductance R t_f / L = 0.59 / 4.34 = 13.6 % high, beyond the 10 % tolerance (the
    # proving ground's integrator before session 14 lagged the current further: 15-19 % then) ...
    assert res.calibration["L"]["relative"] == pytest.approx(filt / l_over_r, abs=0.02)
    assert res.verdict == []  # ... which the current lag the torque equation measures accounts for


def test_wrong_inductance_still_named_beside_a_filter() -> None:
    for error in (0.4, -0.3):  # above the filter's share and below nominal
        log, p = _told(3090, error)
        assert diagnose(DCMotorPlant(p), log).verdict == ["param:L"]


def test_low_inductance_named_under_two_samples() -> None:
    log, p = _told(3094, -0.4)
    _, _, filt, l_over_r = _clean(3094)
    assert filt == 0.0 and l_over_r == pytest.approx(1.06, abs=0.02)
    res = diagnose(DCMotorPlant(p), log)
    assert res.verdict == ["param:L"]
    assert res.calibration["L"]["relative"] == pytest.approx(-0.4, abs=0.1)


def test_high_inductance_named_under_two_samples_where_the_speed_shows_it() -> None:
    """3013: a clean 1 kHz draw, true L/R 1.05 samples, no filter. Told ``L`` 40 % too low (true = 1.4 nominal), the
    code before session 54 left ``L`` free above nominal under two samples (a filter could raise it): of the 135
    clean draws 3000..3199 under two samples told so, it named none, this code 14 (``/tmp`` probe, session 54's
    note). The fitted ``L`` is beyond the box the timing and the measured filter leave, and predicts the held-out
    speed better than the nominal one (a filter would not), so it is named, and the calibrated plant takes it."""
    log, p = _told(3013, 0.4)
    _, _, filt, l_over_r = _clean(3013)
    assert filt == 0.0 and l_over_r == pytest.approx(1.05, abs=0.02)
    res = diagnose(DCMotorPlant(p), log)
    assert res.verdict == ["param:L"]
    cal = res.calibration["L"]
    assert cal["relative"] == pytest.approx(0.4, abs=0.2) and cal["applied"] == cal["relative"]
    assert cal["unresolved"] is None  # (named: the log decided it, no "cannot tell" beside the verdict)


def test_filter_raised_inductance_not_named_where_the_speed_denies_it() -> None:
    """3046 of the ``constant`` draws: ``k`` 14.7 % low, the current read through a 0.56-sample filter at an L/R of
    0.80 samples (apparent ``L`` 70 % high). The torque equation measured a 0.38-sample lag, too little to box the
    fitted ``L`` (87 % high); the nominal ``L`` predicts the held-out speed better, so the filter is the likelier
    cause: ``L`` is not named, and stays nominal in the calibrated plant."""
    case = make_case(3046, kind="constant")
    lg = case.logger
    assert (1.0 - lg.alpha) / lg.alpha == pytest.approx(0.56, abs=0.01) and case.constant_error == {"k": pytest.approx(
        -0.147, abs=0.001)}
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert res.verdict == ["param:k"]
    cal = res.calibration["L"]
    assert cal["unresolved"] == FILTER_MIMICS and cal["relative"] > 0.5 and cal["applied"] == 0.0


def test_right_inductance_under_two_samples_not_named() -> None:
    log, p = _told(3094, 0.0)
    assert diagnose(DCMotorPlant(p), log).verdict == []


def _alignment(lags: np.ndarray, res: np.ndarray, samples: float) -> Alignment:
    return Alignment(samples, 0.0, False, "", (tuple(lags), tuple(res)), True)


def test_timing_spread() -> None:
    """A sharp minimum is known to the grid step; a plateau (a slow PRBS) to half its width; a lag held to the
    conventions while a longer one fits better is not measured at all."""
    lags = np.arange(0.0, 6.0 + 1e-9, LAG_STEP)
    sharp = 1.0 + np.abs(lags - 2.0)
    assert spread(_alignment(lags, sharp, 2.0)) == LAG_STEP
    plateau = 1.0 + np.maximum(np.abs(lags - 2.0) - 0.5, 0.0)
    assert spread(_alignment(lags, plateau, 2.0)) == pytest.approx(0.5)
    held = 1.0 + np.abs(lags - 4.5)
    assert spread(_alignment(lags, held, 2.75)) == np.inf
