"""The thrust map's ``w|w|`` as the low-passed thrust sees it (eq. thrust_model on the regression's low-passed rows,
:func:`ocp.identify.columns.signals`): the low-pass of ``w|w|``, not the square of the low-passed speed, whose
difference does not fall with the sample time (session 65; ``tests/identify/test_thrust_square.py``). SI: speeds
[rad/s], their squares [rad^2/s^2], thrust [N], frequencies [Hz], times [s].
"""

from __future__ import annotations

import functools
import math

import numpy as np
from scipy import special

from ocp.identify.align import smooth
from ocp.identify.noise_level import floored_noise, white_noise
from ocp.logs import Log

#: the speed is low-passed at this many times the channels' cutoff before its ``w|w|`` is formed for the thrust map
#: (:func:`low_passed_square`): the square of the full low-pass left 2.4e-3 N on the exact +-6 V square of
#: ``tests/identify/test_thrust_square.py`` at 1 and 10 kHz alike; at 2, 3 and 4 times the cutoff 1.0-1.3e-3,
#: 1.7-3.4e-4 and 0.3-1.2e-4 N (1 and 10 kHz); the raw speed's square none, but a coarse encoder's quantized speed
#: (whose noise the Gaussian correction misreads: its second differences are mostly zero) then moved the thrust map by
#: 0.7 noise levels (proving ground 1289, a 1024-count encoder at 10 kHz: ``param:c_f`` named for its asymmetry)
SQUARE_CUTOFF = 4.0
#: the largest bias the speed's noise may put in that square, ``c_f sigma^2`` with the larger of the two noise
#: estimates (:func:`_speed_noise`), as a share of the low-passed thrust's noise: beyond it the square of the low-passed
#: speed is kept, whose noise is the low-pass's (a 74 Hz tachometer log with 134 rad/s of filtered noise, blind rig
#: 627, read ``c_f`` 59 % high through the gentler low-pass, 0.4 % through the full one; evidence.RESOLVED's share)
SQUARE_NOISE = 0.2


@functools.lru_cache(maxsize=32)
def _white_shares(dt: float, fc: float, n: int) -> tuple[float, float]:
    """The shares of white noise's variance :func:`.align.smooth` at ``fc`` [Hz] passes and removes on a log of ``n``
    rows: ``sum h^2`` (at most 1) and ``1 - 2 h_0 + sum h^2`` for its impulse response ``h`` (at most ``n`` samples,
    centred at ``h_0``); once per sample time, cutoff and length (the regression builds its rows several times)."""
    pulse = np.zeros(min(n, 2 * int(20.0 / (fc * dt)) + 1) // 2 * 2 + 1)
    pulse[pulse.size // 2] = 1.0
    h = smooth(pulse, dt, fc)
    power = float(np.sum(h * h))
    return min(power, 1.0), 1.0 - 2.0 * float(h[pulse.size // 2]) + power


def low_passed_square(log: Log, raw: np.ndarray, low: np.ndarray, fc: float, c_f: float) -> np.ndarray | None:
    """(N,) [rad^2/s^2] the low-pass at ``fc`` [Hz] of ``w|w|`` for the speed ``raw`` (N,) [rad/s] of ``log`` whose
    low-pass is ``low`` (N,): formed on the speed low-passed at :data:`SQUARE_CUTOFF` times ``fc``, less that speed's
    noise bias (:func:`square_bias`; its white noise the smaller estimate of :func:`_speed_noise`, times the share the
    gentler low-pass passes). None where the larger estimate puts that bias, ``c_f sigma^2`` [N], at
    :data:`SQUARE_NOISE` of the low-passed thrust's noise or more (:func:`.noise_level.floored_noise`, through the
    low-pass): the speed's noise, not the method, would then decide."""
    dt = log.dt
    pre_fc = SQUARE_CUTOFF * fc
    pre = smooth(raw, dt, pre_fc)
    share = _white_shares(dt, pre_fc, raw.size)[0]
    passed, removed = _white_shares(dt, fc, raw.size)
    small, large = _speed_noise(raw, low, removed)
    if c_f * large**2 * share >= SQUARE_NOISE * floored_noise(log.thrust) * math.sqrt(passed):
        return None
    # eq. thrust_model's w|w| through the low-pass the thrust took, less the speed noise's bias
    return smooth(pre * np.abs(pre), dt, fc) - square_bias(low, small * math.sqrt(share))


def _speed_noise(raw: np.ndarray, low: np.ndarray, removed: float) -> tuple[float, float]:
    """Two estimates [rad/s], the smaller first, of the white noise of the speed ``raw`` (N,) whose low-pass is ``low``
    (N,): its second differences' (:func:`.noise_level.white_noise`, high where the signal bends at the sample scale,
    low on a quantized one) and what the low-pass removes, scaled by the share ``removed`` of white noise's variance it
    removes (:func:`_white_shares`; high where the signal has content above the cutoff)."""
    a, b = white_noise(raw), float(np.std(raw - low)) / math.sqrt(max(removed, 1e-12))
    return min(a, b), max(a, b)


def square_bias(mu: np.ndarray, sigma: float) -> np.ndarray:
    """``E[x|x|] - mu|mu|`` (M,) [rad^2/s^2] for ``x`` Gaussian about ``mu`` (M,) [rad/s] with standard deviation
    ``sigma`` [rad/s]: what a speed's white noise adds to ``w|w|`` (``sign(mu) sigma^2`` away from zero, smooth through
    it). ``E[x|x|] = (mu^2 + sigma^2)(2 Phi(mu/sigma) - 1) + 2 mu sigma phi(mu/sigma)``."""
    if sigma <= 0.0:
        return np.zeros_like(mu)
    z = mu / sigma
    return ((mu * mu + sigma * sigma) * special.erf(z / math.sqrt(2.0))
            + 2.0 * mu * sigma * np.exp(-0.5 * z * z) / math.sqrt(2.0 * math.pi) - mu * np.abs(mu))
