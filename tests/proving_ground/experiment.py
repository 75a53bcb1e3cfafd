"""Proving-ground rigs for experiment design: a log that cannot settle an explanation, and the same rig run
under a proposed command.

:func:`single_speed` draws a rig (motor, logger) as :func:`.cases.make_case` does, with one hidden effect,
and logs it only while it turns near ONE operating speed (a small square wave of +-``swing`` around 60 % of
the supply, after the start-up transient is cut off): a constant torque (Coulomb friction) and a change of
the viscous and quadratic drag then look alike by construction. :func:`run_command` plays any voltage
command (t, V) on the same rig and logger, from rest. Shares no code with ``ocp``; plain arrays out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from tests.proving_ground.cases import _lag, _scales, draw_effect, draw_motor
from tests.proving_ground.logger import Logger, draw_logger, record
from tests.proving_ground.physics import Truth, run


@dataclass
class Rig:
    """A drawn rig: truth, logger, mechanical time constant [s], the nominal constants the user believes."""

    truth: Truth
    logger: Logger
    tau_m: float
    nominal: dict[str, float]


def _substeps(rig: Rig) -> int:
    return max(4, math.ceil(rig.logger.dt / min(rig.tau_m / 150.0, 5e-4)))


def draw(seed: int, effect: str) -> Rig:
    """Rig ``seed`` with ``effect`` hidden (its size doubled: well above the noise); exact nominal constants."""
    rng = np.random.default_rng(seed)
    truth, tau_m = draw_motor(rng)
    sc = _scales(truth)
    lg = draw_logger(rng, tau_m, sc["w0"], sc["i"], sc["F"], truth.v_max)
    params = draw_effect(effect, truth, lg.dt, rng)
    first = next(iter(params))
    truth.effects = {effect: {**params, first: 2.0 * params[first]}}
    nominal = {"J": truth.J, "B": truth.B, "c_tau": truth.c_tau, "c_f": truth.c_f, "k_t": truth.k, "k_e": truth.k,
               "R": truth.R, "L": truth.L}
    return Rig(truth, lg, tau_m, nominal)


def _columns(rig: Rig, cmd: np.ndarray, skip: int, seed: int) -> dict[str, np.ndarray]:
    lg = rig.logger
    out, issued = run(rig.truth, lambda k, _s: float(cmd[k]), cmd.size, lg.dt, _lag(rig.truth, lg), _substeps(rig))
    cols = record(lg, out[:, skip:], issued[skip:], np.random.default_rng(seed))
    cols["t"] = np.arange(cols["voltage"].size) * lg.dt  # the uniform time base a reader resamples onto
    return cols


def single_speed(rig: Rig, seed: int, swing: float = 0.08) -> dict[str, np.ndarray]:
    """Log columns (t, voltage, current, omega, thrust[, theta]) of ``rig`` held near one speed: the command
    is ``0.6 V_max (1 +- swing)``, switching every two time constants at random."""
    rng = np.random.default_rng(seed)
    lg = rig.logger
    warm = int(10 * rig.tau_m / lg.dt)  # the start-up transient is not logged
    n = min(int(max(60 * rig.tau_m, 3.0) / lg.dt), 6000)
    hold = max(1, int(2 * rig.tau_m / lg.dt))
    v0 = 0.6 * rig.truth.v_max
    levels = v0 * (1 + swing * np.sign(rng.standard_normal(n // hold + 2)))
    cmd = np.concatenate([np.full(warm, v0), np.repeat(levels, hold)[:n]])
    return _columns(rig, np.round(cmd / lg.q_v) * lg.q_v, warm, seed + 1)


def run_command(rig: Rig, t: np.ndarray, voltage: np.ndarray, seed: int) -> dict[str, np.ndarray]:
    """Log columns of ``rig`` from rest under the command ``voltage`` (N,) on ``t`` (N,) [s, V], sampled (held)
    at the logger's rate and quantised to its PWM step."""
    lg = rig.logger
    tk = np.arange(int(t[-1] / lg.dt)) * lg.dt
    idx = np.clip(np.searchsorted(t, tk, side="right") - 1, 0, t.size - 1)
    return _columns(rig, np.round(voltage[idx] / lg.q_v) * lg.q_v, 0, seed)


def voltage_steps(rig: Rig, seed: int, duration: float = 3.0, levels: tuple[float, ...] = (-1.0, -0.3, 0.3, 1.0)
                  ) -> tuple[np.ndarray, np.ndarray]:
    """A command of random voltage steps (t, V) [s, V]: ``levels`` of 0.6 ``V_max`` drawn at random, each held
    half a mechanical time constant (at least 5 ms), for ``duration``: a current transient at every step."""
    rng = np.random.default_rng(seed)
    hold = max(rig.tau_m / 2, 0.005)
    n = int(duration / hold) + 1
    return np.arange(n) * hold, rig.truth.v_max * 0.6 * rng.choice(np.asarray(levels), n)


def at_rate(rig: Rig, rate: float) -> Rig:
    """``rig`` with its logger's habits (skew and filter in samples, noise, quantisation) at ``rate`` [Hz]."""
    return replace(rig, logger=replace(rig.logger, rate=float(rate)))
