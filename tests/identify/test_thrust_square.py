"""The thrust map on low-passed rows compares the low-pass of ``c_f w|w|`` with the low-passed thrust
(:func:`ocp.identify.columns.speed_square`; eq. thrust_model).

Until session 65 the regression compared the low-passed thrust with ``c_f`` times the square of the low-passed speed;
the square of a low-pass is not the low-pass of the square, and that method error did not fall with the sample time
(2.4e-3 N at most, 5.3e-4 N RMS, on the noise-free square below at 1, 4 and 10 kHz alike). Oracles: the linear plant
propagated exactly by the matrix exponential (:func:`tests.identify.test_replica.exact`, no code shared with the
regression), and a Monte-Carlo mean for the speed noise's bias on ``w|w|``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from ocp.identify.columns import signals, targets
from ocp.identify.thrust_square import square_bias
from ocp.logs import Log, log_from_arrays
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


def _thrust_errors(rate: float, theta: bool) -> tuple[float, float]:
    """Largest thrust-map residual [N] of the exact noise-free log, start-up and run-out tenths left out: the
    regression's, and c_f times the square of the low-passed speed's (the map before session 65), computed here."""
    u = _square(rate)
    log = logged(LINEAR, u, 1.0 / rate, theta)[1]
    s = signals(log, LINEAR)
    cut = u.size // 10
    mid = slice(cut, u.size - 1 - cut)
    return (float(np.max(np.abs(targets(LINEAR, s)[2][mid]))),
            float(np.max(np.abs((s.f - LINEAR.c_f * s.w0 * np.abs(s.w0))[mid]))))


@pytest.mark.parametrize(("rate", "theta"), [(1e3, False), (4e3, False), (1e4, False), (4e3, True), (1e4, True)])
def test_the_thrust_maps_method_error_is_a_tenth_of_the_squared_low_passes(rate: float, theta: bool) -> None:
    """Squaring the low-passed speed left 2.4e-3 N, 4e-3 of the steady thrust, at every rate; the regression's map
    leaves under 4e-4 of it. (An encoder at 1 kHz: its central difference's own error, 1.7e-3 N, stays.)"""
    top = LINEAR.c_f * (6.0 * LINEAR.k_t / (LINEAR.B * LINEAR.R + LINEAR.k_t * LINEAR.k_e)) ** 2  # the steady thrust
    ours, squared = _thrust_errors(rate, theta)
    assert squared > 3e-3 * top and ours < min(0.1 * squared, 4e-4 * top)


def _steady(speed_noise: float, thrust_noise: float) -> tuple[Log, float]:
    """A constant 6 V command to the linear plant at 1 kHz for 20 s, its tachometer's white noise ``speed_noise`` and
    its thrust's ``thrust_noise`` times the top speed and thrust; and ``c_f sigma^2`` [N]."""
    n = 20_000
    t = np.arange(n) / 1e3
    u = np.full(n, 6.0)
    w, i, _ = exact(LINEAR, t, u, 0.0, 0.0)
    rng = np.random.default_rng(5)
    sigma, f = speed_noise * float(w[-1]), LINEAR.c_f * w * np.abs(w)
    return log_from_arrays(t, u, i, f + thrust_noise * f[-1] * rng.standard_normal(n),
                           omega=w + sigma * rng.standard_normal(n)), LINEAR.c_f * sigma**2


def test_a_speed_too_noisy_for_the_square_keeps_the_squared_low_pass() -> None:
    """The tachometer's noise at 30 % of the speed beside a quiet thrust: ``c_f sigma^2`` is 9 % of the thrust, far
    beyond a fifth of its noise; the map squares the low-passed speed, whose noise the low-pass has taken."""
    assert signals(_steady(0.3, 0.0)[0], LINEAR).square is None
    assert signals(_steady(0.3, 1.0)[0], LINEAR).square is not None


def test_a_noisy_speed_leaves_no_offset_in_the_thrust_map() -> None:
    """Speed noise at 30 % of the speed, the thrust's at its top value (a fifth of whose low-passed level the square's
    noise bias stays under): the residual's mean is within four standard errors of zero, where ``c_f sigma^2`` is 5
    standard errors or more."""
    log, bias = _steady(0.3, 1.0)
    r = targets(LINEAR, signals(log, LINEAR))[2][2000:-2000]
    # the low-passed rows are correlated: the standard error from means over blocks ten times the low-pass's span
    blocks = r[: r.size // 500 * 500].reshape(-1, 500).mean(axis=1)
    err = float(np.std(blocks)) / math.sqrt(blocks.size)
    assert abs(float(np.mean(r))) < 4.0 * err and bias > 5.0 * err
