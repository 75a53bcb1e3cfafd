"""A quantized sensor whose reading mostly repeats has a noise level (issue #11, session 74).

A fast encoder on a slow rotor: the speed differenced over one 10 kHz row reads zero counts on most rows and one
count now and then. Its second differences are then mostly zero, their MAD is zero, and the speed's noise level
came out at the floor (1e-6 of its peak): every misfit of the speed counted as thousands of noise units.
On the proving ground's 2,000 logs seven such speeds (5-10 kHz encoders); one, ``make_case(3109, kind="constant")``,
a `J` error on a 10 kHz encoder log, named a false angle ripple beside `J`.
"""

from __future__ import annotations

import math

import numpy as np

from ocp.identify import diagnose
from ocp.identify.noise_level import sensor_noise, white_noise
from ocp.identify.predict import noise_levels
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _encoder(rate: float, counts: int, seconds: float) -> tuple[np.ndarray, np.ndarray]:
    """A rotor at 2-3 rad/s read by an encoder of ``counts`` per turn at ``rate`` [Hz]: (the logged speed (N,), its
    error against the rotor's exact mean speed over each row (N,)) [rad/s]."""
    dt = 1.0 / rate
    t = np.arange(int(seconds * rate) + 1) * dt
    theta = 2.5 * t + 0.5 / math.pi * (1.0 - np.cos(math.pi * t))  # w = 2.5 + 0.5 sin(pi t)
    q = 2.0 * math.pi / counts
    logged = np.diff(np.floor(theta / q) * q) / dt
    return logged, logged - np.diff(theta) / dt


def test_a_speed_that_mostly_repeats_reads_its_rounding() -> None:
    w, err = _encoder(10_000.0, 1024, 4.0)
    truth = float(np.std(err))  # the oracle: the reading against the rotor's exact mean speed, row by row
    assert np.mean(np.diff(w, 2) == 0.0) > 0.5  # the class: most second differences zero (the MAD is zero)
    assert white_noise(w) < 1e-6 * truth  # the MAD alone reads nothing
    assert 0.5 * truth < sensor_noise(w) < 2.0 * truth


def test_a_noisy_sensor_keeps_the_mad() -> None:
    rng = np.random.default_rng(7)
    y = np.sin(np.linspace(0.0, 20.0, 5000)) + 0.01 * rng.standard_normal(5000)
    assert sensor_noise(y) == white_noise(y)
    assert abs(sensor_noise(y) / 0.01 - 1.0) < 0.1


def test_a_fast_encoder_log_names_no_false_ripple() -> None:
    case = make_case(3109, kind="constant")
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    assert case.logger.rate == 10_000.0 and case.logger.speed == "encoder"
    # the speed's level is its rounding's order (the proving ground's own level 0.78 rad/s), not the 1e-6 floor
    assert 0.2 < noise_levels(log)["omega"] < 4.0
    assert sorted(diagnose(DCMotorPlant(MotorParams(**case.nominal)), log).verdict) == sorted(case.expected)
