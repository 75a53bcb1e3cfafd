"""Loggers: how a rig's signals become a log (rate, skew, speed sensor, filters, noise, quantisation, jitter)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class Logger:
    """A logger's habits.

    rate [Hz]; skew [samples]: the drive applies the command logged at row k that much later (integer part:
    the logging convention, fraction: the drive's update instant); speed: ``encoder`` (counts per rev, speed
    from a ``diff_span``-sample backward difference, angle column logged) or ``tacho`` (analog, noisy);
    current: first-order digital filter ``alpha`` (1 = none), noise, ADC step; thrust: noise, step;
    command: PWM resolution [V]; jitter: timestamp noise [fraction of dt].
    """

    rate: float
    skew: float
    speed: str
    counts: int
    diff_span: int
    noise_w: float
    alpha: float
    noise_i: float
    q_i: float
    noise_f: float
    q_f: float
    q_v: float
    jitter: float

    @property
    def dt(self) -> float:
        return 1.0 / self.rate

    def speed_noise(self) -> float:
        """1-sigma of the logged speed [rad/s] (for detectability)."""
        if self.speed == "tacho":
            return self.noise_w
        return 2 * math.pi / self.counts / (self.diff_span * self.dt) / math.sqrt(6.0)


def draw_logger(rng: np.random.Generator, tau_m: float, w0: float, i_op: float, f_op: float, v_max: float) -> Logger:
    rates = [r for r in (50.0, 100.0, 200.0, 500.0, 1000.0, 2000.0, 5000.0, 10000.0) if r >= 4.0 / tau_m]
    rate = float(rng.choice(rates))
    speed = "encoder" if rng.random() < 0.6 else "tacho"
    return Logger(
        rate=rate, skew=float(rng.integers(0, 3)) + rng.uniform(0.0, 0.3), speed=speed,
        counts=int(rng.choice([1024, 4096, 16384, 65536])), diff_span=int(rng.integers(1, 3)),
        noise_w=rng.uniform(0.002, 0.008) * w0, alpha=float(rng.choice([1.0, rng.uniform(0.6, 0.95)])),
        noise_i=rng.uniform(0.003, 0.01) * i_op, q_i=i_op / rng.choice([200.0, 1000.0]),
        noise_f=rng.uniform(0.003, 0.01) * f_op, q_f=f_op / rng.choice([500.0, 2000.0]),
        q_v=2 * v_max / rng.choice([256.0, 1024.0, 4096.0]), jitter=float(rng.choice([0.0, 0.01])))


def _firmware_filter(lg: Logger, cur: np.ndarray) -> np.ndarray:
    """The current sensor's first-order digital filter (``alpha``) over the samples ``cur`` (n,) [A]."""
    filt = np.empty(cur.size)
    acc = cur[0]
    for k in range(cur.size):
        acc += lg.alpha * (cur[k] - acc)
        filt[k] = acc
    return filt


def _encoder_speed(lg: Logger, theta: np.ndarray) -> np.ndarray:
    """Speed [rad/s] (n,) from the angle samples ``theta`` (n,) [rad]: a ``diff_span``-sample backward difference."""
    d = lg.diff_span
    w = np.empty(theta.size)
    w[d:] = (theta[d:] - theta[:-d]) / (d * lg.dt)
    w[:d] = w[d]
    return w


def logged(lg: Logger, truth: np.ndarray) -> np.ndarray:
    """What the logger makes of the true samples (4, n) [w, sensed current, theta, thrust] without its noise and
    quantisation: (3, n) [speed rad/s, current A, thrust N]. An encoder's speed is a difference of angles (a
    ripple faster than the sampling averages out of it), the current passes the firmware's filter."""
    w = truth[0] if lg.speed == "tacho" else _encoder_speed(lg, truth[2])
    return np.vstack([w, _firmware_filter(lg, truth[1]), truth[3]])


def noise_levels(lg: Logger) -> np.ndarray:
    """1-sigma (3,) of the noise in the logged [speed rad/s, current A, thrust N] (:func:`logged`'s channels):
    the sensors' white noise after the current filter, and each ADC step's uniform rounding (step / sqrt(12))."""
    a = lg.alpha
    return np.array([lg.speed_noise(), math.hypot(lg.noise_i * math.sqrt(a / (2.0 - a)), lg.q_i / math.sqrt(12.0)),
                     math.hypot(lg.noise_f, lg.q_f / math.sqrt(12.0))])


def record(lg: Logger, truth: np.ndarray, cmds: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """Log columns (SI) from the true samples (4, n) [w, sensed current, theta, thrust] and the commands (n,)."""
    n = cmds.size
    dt = lg.dt
    t = np.arange(n) * dt + lg.jitter * dt * np.clip(rng.standard_normal(n), -3, 3)
    filt = _firmware_filter(lg, truth[1] + lg.noise_i * rng.standard_normal(n))
    out = {"t": t, "voltage": cmds.copy(), "current": np.round(filt / lg.q_i) * lg.q_i,
           "thrust": np.round((truth[3] + lg.noise_f * rng.standard_normal(n)) / lg.q_f) * lg.q_f}
    if lg.speed == "tacho":
        out["omega"] = truth[0] + lg.noise_w * rng.standard_normal(n)
    else:
        step = 2 * math.pi / lg.counts
        theta = np.floor(truth[2] / step) * step
        out["omega"], out["theta"] = _encoder_speed(lg, theta), theta
    return out
