"""The thrust map on low-passed rows compares the low-pass of ``c_f w|w|`` with the low-passed thrust
(:func:`ocp.identify.columns.speed_square`; eq. thrust_model).

Until session 65 the regression compared the low-passed thrust with ``c_f`` times the square of the low-passed speed;
the square of a low-pass is not the low-pass of the square, and that method error did not fall with the sample time
(5.3e-4 N on the noise-free square below at 1, 4 and 10 kHz alike). Oracles: the linear plant propagated exactly by the
matrix exponential (:func:`tests.identify.test_replica.exact`, no code shared with the regression), and a Monte-Carlo
mean for the speed noise's bias on ``w|w|``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify.columns import signals, square_bias, targets
from ocp.logs import log_from_arrays
from tests.identify.test_replica import LINEAR, exact, logged


@pytest.mark.parametrize("mu", [-30.0, -1.0, 0.0, 0.5, 2.0, 40.0])
def test_the_noise_bias_of_w_abs_w_is_the_gaussian_mean(mu: float) -> None:
    sigma, n = 2.0, 400_000
    x = mu + sigma * np.random.default_rng(3).standard_normal(n)
    y = x * np.abs(x)
    err = 4.0 * float(np.std(y)) / math.sqrt(n)  # four standard errors of the Monte-Carlo mean
    assert float(square_bias(np.array([mu]), sigma)[0]) == pytest.approx(np.mean(y) - mu * abs(mu), abs=err)


def _square(rate: float) -> np.ndarray:
    """A +-6 V, 5 Hz square over 0.8 s sampled at ``rate`` [Hz] (N,) [V]."""
    t = np.arange(int(0.8 * rate)) / rate
    return np.where((5.0 * t) % 1.0 < 0.5, 6.0, -6.0)


def _thrust_error(rate: float, theta: bool) -> float:
    """Largest thrust-map residual [N] of the exact noise-free log, start-up and run-out tenths left out."""
    u = _square(rate)
    r = targets(LINEAR, signals(logged(LINEAR, u, 1.0 / rate, theta)[1], LINEAR))[2]
    cut = u.size // 10
    return float(np.max(np.abs(r[cut:-cut])))


def test_a_tachometer_logs_thrust_map_holds_to_rounding_at_any_rate() -> None:
    top = LINEAR.c_f * (6.0 * LINEAR.k_t / (LINEAR.B * LINEAR.R + LINEAR.k_t * LINEAR.k_e)) ** 2  # the steady thrust
    for rate in (1e3, 4e3, 1e4):  # (was 5.3e-4 N, 4e-3 of it, at every rate)
        assert _thrust_error(rate, False) < 1e-6 * top


def test_an_encoder_logs_thrust_map_error_falls_with_the_sample_time() -> None:
    """The speed is the angle's central difference, the mean over two samples: its error falls as dt^2."""
    assert _thrust_error(1e4, True) < _thrust_error(1e3, True) / 30.0


def test_a_noisy_speed_leaves_no_offset_in_the_thrust_map() -> None:
    """A constant command: the thrust map's residual mean is within four standard errors of zero with the tachometer's
    noise at 30 % of the speed, where ``c_f sigma^2`` uncorrected is 9 % of the thrust, about 18 standard errors."""
    rate, n = 1e3, 20_000
    t = np.arange(n) / rate
    u = np.full(n, 6.0)
    w, i, _ = exact(LINEAR, t, u, 0.0, 0.0)
    rng = np.random.default_rng(5)
    sigma = 0.3 * float(w[-1])
    log = log_from_arrays(t, u, i, LINEAR.c_f * w * np.abs(w), omega=w + sigma * rng.standard_normal(n))
    r = targets(LINEAR, signals(log, LINEAR))[2][n // 10:-n // 10]
    # the low-passed rows are correlated: the standard error from means over blocks ten times the low-pass's span
    blocks = r[: r.size // 500 * 500].reshape(-1, 500).mean(axis=1)
    err = 4.0 * float(np.std(blocks)) / math.sqrt(blocks.size)
    assert abs(float(np.mean(r))) < err < 0.25 * LINEAR.c_f * sigma**2
