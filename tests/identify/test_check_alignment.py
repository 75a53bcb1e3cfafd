"""``check`` and ``fit`` remove the command timing logging conventions explain before confronting the plant.

Session 21: ``check`` compared the plant with the log as logged: a loop that logs the command it is about to write
beside the sensors it just read (a row early) made the exact plant's free run fail. On the 30 clean proving-ground
logs of seeds 0..199 the exact plant's free run was a median 8.5 noise units off; realigned as ``diagnose`` does,
2.0. ``fit`` fitted the armature's constants to the convention.
"""

from __future__ import annotations

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify import FitOptions, check, fit
from ocp.identify.check import CheckResult
from ocp.identify.fit import channel_rms
from ocp.identify.predict import noise_levels
from ocp.logs import Log, log_from_arrays
from ocp.model.params import MotorParams, load_params
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case
from tests.synthetic_rig import RigSpec, generate


def _early(log: Log, rows: int) -> Log:
    """``log`` with each command logged ``rows`` rows early (the last one held)."""
    v = np.concatenate([log.voltage[rows:], np.repeat(log.voltage[-1], rows)])
    return log_from_arrays(log.t, v, log.current, log.thrust, omega=log.omega, theta=log.theta)


def _units(res: CheckResult) -> dict[str, float]:
    return {ch: res.free_run_rms[ch] / res.noise[ch] for ch in res.free_run_rms}


def _combined(units: dict[str, float]) -> float:
    return float(np.sqrt(np.mean(np.square(list(units.values())))))


def _raw_units(plant: DCMotorPlant, log: Log) -> dict[str, float]:
    """The free run's error [noise units] on ``log`` as logged, no alignment."""
    noise = noise_levels(log)
    return {ch: v / noise[ch] for ch, v in channel_rms(plant, log, 0.5).items()}


@pytest.fixture(scope="module")
def rig() -> tuple[DCMotorPlant, Log]:
    p = load_params("paper-rig")
    return DCMotorPlant(p), generate(p, RigSpec(excitations=("chirp", "sine"), seconds=2.0, seed=5))


def test_a_command_logged_a_row_early_is_checked_as_if_logged_on_time(rig: tuple[DCMotorPlant, Log]) -> None:
    """Oracle: the same run logged on time. The alignment found is the row (within a tenth of a sample), and the
    free run's and the equations' errors are those of the log on time (within 10 %); the free run on the log as
    logged (the check before session 21) is worse in current (1.33 against 0.95 noise units: this rig's armature
    is slow against its 1 kHz logger, the proving-ground draws below show what a fast one does)."""
    plant, log = rig
    on_time = check(plant, log)
    early = check(plant, _early(log, 1))
    assert isinstance(on_time, CheckResult) and isinstance(early, CheckResult)
    assert abs(early.alignment.samples - 1.0) < 0.1 and not early.alignment.delay
    assert abs(on_time.alignment.samples) < 0.1
    for ch, v in _units(on_time).items():
        assert _units(early)[ch] == pytest.approx(v, rel=0.1, abs=0.1)
    for eq, v in on_time.one_step_rms.items():
        assert early.one_step_rms[eq] == pytest.approx(v, rel=0.1)
    assert _raw_units(plant, _early(log, 1))["current"] > 1.2 * _units(early)["current"]
    assert early.to_dict()["alignment"]["samples"] == pytest.approx(early.alignment.samples, abs=1e-3)


def test_fit_on_a_command_logged_early_finds_what_the_log_on_time_gives(rig: tuple[DCMotorPlant, Log]) -> None:
    """A Coulomb friction of 4 mN m hidden in the rig, fitted with ``R``: the same values from the log logged a row
    early as from the log on time (within 0.2 %), the same free-run error after the fit (within 10 %; before
    session 21, 0.283 against 0.104 rad/s, and ``R`` 0.7 % off), and its alignment reported."""
    plant, _ = rig
    p = plant.params
    log = generate(p, RigSpec(effects={"coulomb_friction": {"tau_c": 0.004}}, excitations=("chirp", "sine"),
                              seconds=2.0, seed=6))
    opt = FitOptions(refine=False)
    on_time = fit(plant, log, ["coulomb_friction", "param:R"], opt)
    early = fit(plant, _early(log, 1), ["coulomb_friction", "param:R"], opt)
    assert early.alignment is not None and abs(early.alignment.samples - 1.0) < 0.1
    np.testing.assert_allclose(early.values, on_time.values, rtol=2e-3)
    for ch, v in on_time.after.items():
        assert early.after[ch] == pytest.approx(v, rel=0.1), ch
    assert on_time.values[list(on_time.names).index("coulomb_friction.tau_c")] == pytest.approx(0.004, rel=0.15)


@pytest.mark.parametrize("seed", [21013, 21014, 21020])
def test_a_clean_proving_ground_log_checks_near_its_noise(seed: int) -> None:
    """Fresh clean draws of the independent proving ground, logged 2.0-2.3 samples early (its own logger): the
    exact plant's free run after the alignment is less than half as far from the log as on the log as logged (the
    check before session 21; measured: 60 -> 5.9, 25.9 -> 0.82, 15.9 -> 2.5 noise units, RMS over the channels)."""
    case = make_case(seed, "clean")
    assert case.logger.skew > 1.5
    plant, log = DCMotorPlant(MotorParams(**case.nominal)), case_log(case)
    aligned = check(plant, log)
    assert isinstance(aligned, CheckResult)
    assert abs(aligned.alignment.samples - case.logger.skew) < 0.5
    assert _combined(_units(aligned)) < 0.5 * _combined(_raw_units(plant, log))
