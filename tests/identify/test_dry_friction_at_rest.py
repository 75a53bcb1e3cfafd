"""Dry friction is set-valued where the rotor is at rest (issue #11, session 19).

Where the rotor stands, dry friction holds whatever torque stays within its level: the torque equation's residual
there is wherever the rotor stopped, which no smooth friction column fits. On a periodic trajectory (a loop reversing
at the same angles) that residual is a function of the angle, and a ripple of some count fitted it on held-out rows
too: the ripple was named beside dry friction on rigs that had none. Beside dry friction the ripple's columns are now
left out at the rows at rest (:func:`ocp.identify.columns.at_rest`, :func:`ocp.identify.select.fit_model`).
"""

from __future__ import annotations

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.identify.angle import speed_noise
from ocp.identify.columns import REST_ROWS, at_rest, signals
from ocp.logs import Log, log_from_arrays
from ocp.model.params import MotorParams, load_params
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case

RATE = 1000.0


def _rest_log(stand: tuple[int, int], noise: float, seed: int = 0) -> tuple[np.ndarray, MotorParams, Log]:
    """A 1 kHz log whose rotor runs a 1 Hz sine of 40 rad/s, standing still over the samples ``stand`` (from a zero
    crossing, a multiple of 500; the sine resumes after them); speed noise ``noise`` [rad/s] per sample. Returns
    the true speed (N,) [rad/s], the plant's constants and the log."""
    n = 2000 + stand[1] - stand[0]
    k = np.arange(n)
    phase = np.where(k < stand[0], k, np.where(k < stand[1], stand[0], k - (stand[1] - stand[0])))
    w = 40.0 * np.sin(2 * np.pi * phase / RATE)
    rng = np.random.default_rng(seed)
    log = log_from_arrays(k / RATE, np.zeros(n), np.zeros(n), np.zeros(n), omega=w + noise * rng.normal(size=n))
    return w, load_params("paper-rig"), log


def test_the_rows_at_rest_are_those_where_the_rotor_stands() -> None:
    """Oracle: the constructed stand-still (the low-pass's transition at its ends aside) and the running rows."""
    stand = (500, 700)
    w, p, log = _rest_log(stand, noise=0.05)
    s = signals(log, p)
    rest = at_rest(s, log, p)
    assert speed_noise(log.omega) == pytest.approx(0.05, rel=0.2)
    assert rest[stand[0] + 10:stand[1] - 10].all()
    running = np.abs(w[:-1]) > 2.0  # (a sine through zero stands within the noise for a few rows only)
    assert not rest[running].any()
    assert rest.sum() < (stand[1] - stand[0]) + 20


def test_a_standstill_shorter_than_the_run_is_no_rest() -> None:
    _, p, log = _rest_log((500, 500 + REST_ROWS - 1), noise=0.05)
    rest = at_rest(signals(log, p), log, p)
    assert not rest[450:550].any()


@pytest.mark.parametrize("seed", [11195, 9218])
def test_dry_friction_alone_is_named_without_a_ripple(seed: int) -> None:
    """Proving-ground draws (not the reported seeds) of dry friction alone, Coulomb and Stribeck, on which a ripple
    was named beside it before (session 18's code)."""
    case = make_case(seed)
    assert "cogging" not in case.expected and case.expected & {"coulomb_friction", "stribeck"}
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert set(res.verdict) == case.expected
