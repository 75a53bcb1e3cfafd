"""Excitations: what drives the rig while it is logged (commands at the log rate, volts).

Open loop: ``chirp``, ``steps``, ``prbs``, ``ramp`` (slow triangle through zero), ``sweep`` (staircase of
held levels, each settling: steady-state points inside a time series). Closed loop: ``pi`` (a PI speed loop,
designed from the *nominal* constants the user believes, tracking a thrust sine or sin^5 through zero).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

OPEN_LOOP = ("chirp", "steps", "prbs", "ramp", "sweep")
KINDS = (*OPEN_LOOP, "pi")


def open_loop(kind: str, n: int, dt: float, v_max: float, tau_m: float, rng: np.random.Generator) -> np.ndarray:
    """Command (n,) [V] of an open-loop excitation."""
    t = np.arange(n) * dt
    a = rng.uniform(0.4, 0.85) * v_max
    if kind == "chirp":
        f0, f1 = 0.05 / tau_m, min(0.6 / tau_m, 0.1 / dt)
        return a * np.sin(2 * math.pi * (f0 * t + 0.5 * (f1 - f0) * t**2 / t[-1]))
    if kind in ("steps", "prbs"):
        out, k = np.empty(n), 0
        level = a
        while k < n:
            hold = max(2, round(rng.uniform(3, 10 if kind == "steps" else 4) * tau_m / dt))
            level = rng.uniform(-a, a) if kind == "steps" else -level
            out[k:k + hold] = level
            k += hold
        return out
    if kind == "ramp":
        period = t[-1] + dt
        return a * (1.0 - 4.0 * np.abs(((t / period + 0.25) % 1.0) - 0.5))
    if kind == "sweep":
        levels = np.linspace(-a, a, int(rng.integers(7, 12)))
        rng.shuffle(levels)
        return levels[np.minimum((t / (t[-1] + dt) * levels.size).astype(int), levels.size - 1)]
    raise ValueError(kind)


def pi_loop(n: int, dt: float, nominal: dict[str, float], v_max: float, tau_m: float, rng: np.random.Generator,
            noise_w: float) -> Callable[[int, np.ndarray], float]:
    """A PI speed loop on the (noisy) measured speed with a nominal steady-state feedforward, tracking
    ``w_ref`` for a thrust reference ``A sin`` or ``A sin^5`` through zero."""
    k, r, j, b, c_tau, c_f = (nominal[x] for x in ("k_e", "R", "J", "B", "c_tau", "c_f"))
    w_top = 0.6 * v_max / (k + r * c_tau * 0.6 * v_max / k**2 + r * b / k)  # roughly reachable
    f_top = c_f * w_top**2
    power = 1 if rng.random() < 0.5 else 5
    period = rng.uniform(8, 25) * tau_m
    wc = min(3.0 / tau_m, 0.6 / dt)
    kp, ki = j * r / k * wc, (k * k / r + b) * r / k * wc
    state = {"integ": 0.0}

    def command(idx: int, sensed: np.ndarray) -> float:
        f_ref = f_top * math.sin(2 * math.pi * idx * dt / period) ** power
        w_ref = math.copysign(math.sqrt(abs(f_ref) / c_f), f_ref)
        e = w_ref - (sensed[0] + noise_w * rng.standard_normal())
        state["integ"] += e * dt
        ff = k * w_ref + r / k * (b * w_ref + c_tau * w_ref * abs(w_ref))
        return max(-v_max, min(v_max, ff + kp * e + ki * state["integ"]))

    return command
