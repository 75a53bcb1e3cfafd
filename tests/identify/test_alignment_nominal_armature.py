"""Alignment where the free search is flat: a smooth command (a chirp) on a fast logger, a command delay of
several samples, a fast armature (``L/R`` under a sample or two). Delayed by ``d`` samples, a smooth command looks
like one through an armature lag longer by ``d`` samples, and the free fit's ``a1`` takes either; the nominal
``L/R`` and ``k_e`` tell them apart (:func:`ocp.identify.align._nominal_curve`). Logs from the independent proving
ground (``tests/proving_ground``: its own physics, integrator and logger)."""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from ocp.identify import diagnose
from ocp.identify.align import HELD_L_ERROR, estimate, gain, within
from ocp.identify.diagnose import score
from ocp.identify.predict import noise_levels
from ocp.logs import Log, log_from_arrays, read_log
from ocp.model.effects import load_plant
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.identify.diagnosed import blind
from tests.proving_ground.cases import draw_motor
from tests.proving_ground.excite import open_loop
from tests.proving_ground.logger import Logger, record
from tests.proving_ground.physics import Truth, run

RATE = 5000.0
LAG = 6.6  # [samples]: a 1.3 ms transport delay at 5 kHz


def _chirp_log(seed: int, lag: float = LAG, armature: float | None = None) -> tuple[Log, Truth]:
    """A log (1.2 s) of a drawn motor under an open-loop chirp, the drive applying row k's command ``lag``
    samples later; tachometer speed (noisy), current nearly unfiltered. ``armature``: the motor's L/R [samples]
    set so (its inductance scaled), else as drawn."""
    rng = np.random.default_rng(seed)
    truth, tau_m = draw_motor(rng)
    if armature is not None:
        truth = dataclasses.replace(truth, L=armature * truth.R / RATE)
    w0 = truth.v_max / truth.k
    lg = Logger(rate=RATE, skew=lag, speed="tacho", counts=4096, diff_span=1, noise_w=0.006 * w0, alpha=0.9,
                noise_i=0.006 * truth.v_max / truth.R * 0.1, q_i=1e-4 * truth.v_max / truth.R, noise_f=1e-3, q_f=1e-4,
                q_v=2 * truth.v_max / 1024, jitter=0.0)
    n = int(1.2 * RATE)
    cmds = np.round(open_loop("chirp", n, lg.dt, truth.v_max, tau_m, rng) / lg.q_v) * lg.q_v
    substeps = max(4, math.ceil(lg.dt / min(tau_m / 150.0, 5e-4)))
    samples, issued = run(truth, lambda k, _s: float(cmds[k]), n, lg.dt, lag * lg.dt, substeps)
    cols = record(lg, samples, issued, rng)
    log = log_from_arrays(cols["t"], cols["voltage"], cols["current"], cols["thrust"], omega=cols["omega"])
    return log, truth


def _plant(truth: Truth, l_factor: float = 1.0) -> DCMotorPlant:
    return DCMotorPlant(MotorParams(J=truth.J, B=truth.B, c_tau=truth.c_tau, c_f=truth.c_f, k_t=truth.k, k_e=truth.k,
                                    R=truth.R, L=l_factor * truth.L))


@pytest.mark.parametrize("seed", [4303, 4313])
def test_a_flat_free_search_is_settled_by_the_nominal_armature(seed: int) -> None:
    log, truth = _chirp_log(seed)
    tau = truth.L / truth.R
    assert tau / log.dt < 1.0  # (the class: a fast armature)
    free = estimate(log)
    assert not free.identified and free.samples == 0.0  # the free fit cannot tell the delay
    a = estimate(log, 2.0, (tau, truth.k))
    assert a.identified and a.nominal and abs(a.samples - LAG) <= 0.5, a
    assert a.delay and "nominal L/R" in a.rule
    low = estimate(log, 2.0, (0.5 * tau, truth.k))  # a 50 % inductance error moves it by under a sample
    assert low.identified and abs(low.samples - LAG) <= 1.0, low


@pytest.mark.xfail(strict=True, reason="known miss since session 14's rig integrator: a wrong free minimum")
def test_a_free_search_with_a_wrong_minimum_still_finds_the_delay() -> None:
    """4317 (L/R 0.55 samples) was this class until session 14, when the proving ground's drive began to switch at
    its exact instant and its integrator to follow its equations (``tests/proving_ground/physics.py``): its free
    search is no longer flat but lowest at no lag, rising to a peak 1.4 samples past the true 6.6, and that
    minimum is taken as identified; the nominal armature is never asked and the delay is missed. Not fixed."""
    log, truth = _chirp_log(4317)
    assert diagnose(_plant(truth), log).verdict == ["input_delay"]


SLOW = 8.0  # [samples]: an armature L/R over NOMINAL_TAU


@pytest.mark.parametrize("seed", [4303, 4304])
def test_a_slow_held_armature_measures_a_delay_beyond_its_inductance_share(seed: int) -> None:
    """Held at a slow armature's ``L/R`` (:data:`SLOW` samples), a 50 % inductance error would move the lag by
    half of it (:attr:`Alignment.bias`): a 10-sample delay is clear of that and measured; a conventional 1.2-sample
    lag is not (none is claimed, as before the held search was tried on slow armatures)."""
    log, truth = _chirp_log(seed, 10.0, SLOW)
    assert not estimate(log).identified  # (the class: a flat free search)
    a = estimate(log, 2.0, (truth.L / truth.R, truth.k))
    assert a.identified and a.nominal and a.delay and abs(a.samples - 10.0) <= 0.5, a
    assert a.bias == pytest.approx(HELD_L_ERROR * SLOW) and "inductance error" in a.rule
    assert gain(a, 2.0) == 1.0  # (a held curve falls as deep for an inductance error: the free runs decide)
    log, truth = _chirp_log(seed, 1.2, SLOW)
    a = estimate(log, 2.0, (truth.L / truth.R, truth.k))
    assert not a.identified and not a.nominal and a.samples == 0.0 and a.bias == 0.0, a
    # held at a faster nominal armature than the truth, the lag is long enough to be a delay candidate; its
    # conventional restriction is no lag at all, not the curve's best lag within the conventions (its L's)
    a = estimate(log, 2.0, (0.5 * truth.L / truth.R, truth.k))
    assert a.delay and a.bias > 0.0
    held = within(a, 2.0, log.dt)
    assert not held.identified and held.samples == 0.0 and "longer L/R" in held.rule


@pytest.mark.parametrize("seed", [4303, 4304])
def test_diagnose_tells_a_slow_armatures_delay_from_its_inductance(seed: int) -> None:
    """On a smooth command a delay and a longer ``L/R`` look alike; held-out data tell them apart
    (:func:`ocp.identify.diagnose._delay_wins`): the 10-sample delay is called under exact constants, and a
    conventional lag under an inductance twice its nominal (which the held search reads as a 5-sample lag, a delay
    candidate clear of the 50 % share) is not: the longer ``L/R`` predicts the held-out data better."""
    log, truth = _chirp_log(seed, 10.0, SLOW)
    assert "input_delay" in diagnose(_plant(truth), log).verdict
    log, truth = _chirp_log(seed, 1.2, SLOW)
    res = diagnose(_plant(truth, 0.5), log)
    assert "input_delay" not in res.verdict, res.verdict
    assert res.alignment is not None and not res.alignment.delay


def test_diagnose_calls_the_delay_and_leaves_l_open() -> None:
    log, truth = _chirp_log(4313)
    res = diagnose(_plant(truth), log)
    assert res.alignment is not None and res.alignment.nominal
    assert res.verdict == ["input_delay"], res.verdict


def test_a_delay_within_the_inductance_share_is_judged_on_held_out_data(tmp_path: Path) -> None:
    """The blind rig's seeds 431 and 429 (``bench/blindrig``: its own integrator and loggers; the truth files the
    oracle): slow chirps at 5.1 and 4.1 kHz, a command lag of 10.9 and 9.2 samples beside an L/R of 25 and 12. The held
    search finds 10.73 and 7.53 (11.06 and 7.41 before its speed leads), within a 50 % inductance error's share of them
    (12.6 and 6.1 samples): before, such a lag was not claimed at all, and both logs named ``L`` (+45 %, +86 %), the lag
    the inductance error mimics. Now it is a candidate the held-out data judge
    (:func:`ocp.identify.diagnose._delay_wins`): on 431 the armature's held-out current with the delay is 19 % better
    than with the conventions' lag (each with its best L/R): the delay is called, ``L`` not named; on 429 the two fit
    alike: ``L`` stays, with the delay listed beside it as ambiguous."""
    res, truth = blind(431, tmp_path)
    drawn = truth["logger"]["skew"] + truth["rig"]["delay"] * truth["logger"]["rate"]
    assert res.alignment is not None
    assert res.alignment.nominal and res.alignment.bias > res.alignment.samples - 2.75
    assert abs(res.alignment.samples - drawn) < 0.5 and res.verdict == truth["labels"] == ["input_delay"]
    res, truth = blind(429, tmp_path)
    assert res.verdict == ["param:L"] and truth["labels"] == ["input_delay"]
    rival = [a for a in res.ambiguous if a["alternative"] == "input_delay"]
    assert rival and rival[0]["adopted"] == "param:L" and "7.53 samples" in rival[0]["reason"]


def test_a_lag_held_to_the_conventions_still_says_it_rests_on_the_nominal_armature() -> None:
    """:func:`within` (a delay that did not predict better) keeps the flag: ``L`` stays open beside such a lag."""
    log, truth = _chirp_log(4313)
    held = within(estimate(log, 2.0, (truth.L / truth.R, truth.k)), 2.0, log.dt)
    assert held.nominal and not held.delay and held.samples <= 2.75


def test_a_current_offset_does_not_decide_the_delay() -> None:
    """The delay's free-run comparison takes each channel's held-out error about its mean
    (:func:`ocp.identify.diagnose.score` ``centred``): a current sensor offset of 30 noise levels, which the delayed
    and the conventional plant share, swamped the delay's advantage (4304: only ``current_offset`` was named)."""
    log, truth = _chirp_log(4304, 10.0, SLOW)
    offset = 30.0 * noise_levels(log)["current"]
    shifted = dataclasses.replace(log, current=log.current + offset)
    mask = np.ones(log.n, dtype=bool)
    noise = noise_levels(log)
    a, b = (score(_plant(truth), lg, mask, noise, 0.1, centred=True).rms["current"] for lg in (log, shifted))
    # the offset is the error's mean, which centring leaves out (all but the first L/R of each segment, which
    # starts from the logged current, offset and all: 0.5 % here)
    assert b == pytest.approx(a, rel=0.02)
    assert score(_plant(truth), shifted, mask, noise, 0.1).rms["current"] > 10.0 * noise["current"]
    assert diagnose(_plant(truth), shifted).verdict == ["input_delay", "current_offset"]


@pytest.mark.parametrize("seed", [476, 663])
def test_a_late_speed_is_not_read_as_a_delay(seed: int, tmp_path: Path) -> None:
    """The blind rig's 476 (a 500 Hz PI log, its tachometer filtered over 2.9 rows, the command logged 2 samples
    early) and 663 (an encoder's differenced speed, 2 samples early): no delay drawn, and the free search flat. Held
    to the logged speed, the back-EMF of the nominal curve lagged with the speed sensor and the command was moved to
    match: 4.6 and 3.6 samples, both beyond the conventions (476's diagnosis named the ``input_delay``). With the
    speed's lead over 1-3 samples free in that curve (:func:`ocp.identify.align._nominal_curve`) the lag found is the
    conventional one."""
    res, truth = blind(seed, tmp_path)  # (the case's files, written into tmp_path)
    p = load_plant(tmp_path / f"case-{seed}.params.json").params
    a = estimate(read_log(tmp_path / f"case-{seed}.csv"), 2.0, (p.L / p.R, p.k_e))
    assert a.nominal and not a.delay and abs(a.samples - truth["logger"]["skew"]) <= 0.75, a
    assert "input_delay" not in res.verdict and "input_delay" not in truth["labels"]


@pytest.mark.parametrize("seed", [800, 249])
def test_a_late_speed_sensor_does_not_vouch_for_a_delay(seed: int, tmp_path: Path) -> None:
    """The blind rig's 800 (a 2.8 kHz PI log, its tachometer filtered over 3.0 rows, the command logged 2 samples
    early) and 249 (a 950 Hz ramp, an encoder's differenced speed, 1 sample early): no delay drawn. Their searches
    read 3.0 and 5.0 samples, beyond the conventions, and the free run with that delay predicted the held-out speed
    better (the simulated speed late as the sensor's), though not the current: both were named an ``input_delay``.
    Judged on the current, the delay is not called (:func:`ocp.identify.diagnose._delay_wins`)."""
    res, truth = blind(seed, tmp_path)
    assert "input_delay" not in truth["labels"] and truth["rig"]["delay"] == 0.0
    assert res.alignment is not None and not res.alignment.delay and "input_delay" not in res.verdict
    assert res.alignment.samples <= 2.75  # (the conventions' edge: 2 samples of skew and 0.75 of the update)
