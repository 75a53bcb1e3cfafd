"""The free run predicts the speed as the logger read it (:func:`ocp.identify.predict.speed_span`, ``sensed_speed``).

Session 21: firmware often logs an encoder's speed as a backward difference over one or two samples, the mean speed
over them, half a sample to a sample late. The free run compared the speed at the sample with it: on clean
proving-ground logs of the exact plant (no effect, no wrong constant) a rotor reversing at +-390 rad/s logged at
200 Hz was 24 rad/s RMS, ~30 noise units, from its own speed, and ``check`` showed the model failing where it holds.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import ocp.identify.predict as predict
from bench.modelcheck import case_log
from ocp.identify.align import estimate
from ocp.identify.fit import channel_rms
from ocp.identify.predict import MAX_SPEED_SPAN, noise_levels, sensed_speed, speed_span
from ocp.identify.realign import realign
from ocp.logs import Log, log_from_arrays
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case

RATE = 500.0
A, F = 300.0, 7.0  # rad/s, Hz: a speed that moves 26 rad/s a sample at its zero crossings


def _theta(t: np.ndarray) -> np.ndarray:
    """Exact angle [rad] of the speed ``A sin(2 pi F t)``."""
    return A / (2 * math.pi * F) * (1.0 - np.cos(2 * math.pi * F * t))


def _log(span: int) -> Log:
    """A log of the closed-form rotor whose speed is the backward difference of its exact angle over ``span``
    samples (0: the speed at the sample)."""
    t = np.arange(2000) / RATE
    th = _theta(t)
    w = A * np.sin(2 * math.pi * F * t) if span == 0 else (th - _theta(t - span / RATE)) * RATE / span
    return log_from_arrays(t, np.zeros_like(t), np.zeros_like(t), np.zeros_like(t), omega=w, theta=th)


@pytest.mark.parametrize("span", range(MAX_SPEED_SPAN + 1))
def test_the_span_is_read_from_the_logged_angle(span: int) -> None:
    assert speed_span(_log(span)) == span


def test_no_logged_angle_means_the_speed_at_the_sample() -> None:
    t = np.arange(200) / RATE
    log = log_from_arrays(t, np.zeros_like(t), np.zeros_like(t), np.zeros_like(t), omega=A * np.sin(t))
    assert speed_span(log) == 0


@pytest.mark.parametrize("span", [1, 2, 3])
def test_the_window_mean_against_the_exact_integral(span: int) -> None:
    """Trapezoid over the samples against ``(theta(t) - theta(t - span dt)) / (span dt)``: within the rule's bound
    ``(span dt)^2 max|w''| / 12``; the first ``span`` rows of each segment keep the speed itself."""
    dt, length = 1.0 / RATE, 250
    t = np.arange(2 * length) * dt
    w = A * np.sin(2 * math.pi * F * t)
    got = sensed_speed(w, span, length).reshape(2, length)
    exact = ((_theta(t) - _theta(t - span * dt)) / (span * dt)).reshape(2, length)
    bound = (span * dt) ** 2 * A * (2 * math.pi * F) ** 2 / 12
    assert np.max(np.abs(got[:, span:] - exact[:, span:])) <= bound
    assert np.max(np.abs(exact - w.reshape(2, length))) > 10 * bound  # the window is no speed at the sample
    np.testing.assert_array_equal(got[:, :span], w.reshape(2, length)[:, :span])
    np.testing.assert_array_equal(sensed_speed(w, 0, length), w)


@pytest.mark.parametrize("seed", [21003, 21027])
def test_a_clean_encoder_log_is_reproduced_by_its_own_plant(seed: int, monkeypatch: pytest.MonkeyPatch) -> None:
    """Fresh clean proving-ground draws (its own rig and logger: an encoder differenced over two samples at 200 Hz
    and 1 kHz, a 21-26 ms rotor): the exact plant's free run, at the check's own alignment, is several times
    nearer the log with the speed read as the logger read it (measured: 20.8 -> 4.9 and 92 -> 17 noise units)."""
    case = make_case(seed, "clean")
    assert case.logger.speed == "encoder" and case.logger.diff_span == 2
    log = case_log(case)
    assert speed_span(log) == 2
    plant = DCMotorPlant(MotorParams(**case.nominal))
    aligned = realign(log, estimate(log, 2.0, (plant.params.L / plant.params.R, plant.params.k_e)).samples)
    noise = noise_levels(log)["omega"]

    def speed_error() -> float:
        return channel_rms(plant, aligned, 0.5)["omega"] / noise

    read = speed_error()
    monkeypatch.setattr(predict, "speed_span", lambda _log: 0)
    at_sample = speed_error()
    assert read < at_sample / 3
