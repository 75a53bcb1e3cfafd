"""Synthetic thrust rig for the model-check tests: a true plant with hidden effects, a 1 kHz digital
drive with a 12-bit quantised command, noisy and quantised sensors, and realistic excitations.

Excitations (concatenated, the state carries over):

* ``sine``  -- closed-loop tracking of ``x2d = A sin(2 pi t / T)`` (linear thrust reversals, paper Case 1);
* ``sin5``  -- closed-loop tracking of ``x2d = A sin^5(2 pi t / T)`` (flat reversals, paper Case 4);
* ``chirp`` -- open-loop voltage chirp through zero, 0.3 -> 4 Hz.

The speed loop is a PI controller on the measured (noisy) speed with the nominal steady-state
feedforward, like the paper's rig (Section V) without the position and force terms.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import casadi as ca
import numpy as np

from ocp.logs import Log, log_from_arrays
from ocp.model.effects import effects_from_mapping, measured_current
from ocp.model.params import MotorParams
from ocp.model.plant import CASADI, DCMotorPlant
from ocp.simulate.open_loop import rk4


@dataclass(frozen=True)
class RigSpec:
    """What the hidden rig does. Noise levels are 1-sigma; quantisation steps in SI."""

    effects: Mapping[str, Mapping[str, float]] = field(default_factory=dict)
    excitations: Sequence[str] = ("sine", "sin5", "chirp")
    seconds: float = 3.0  # per excitation
    rate: float = 1000.0  # Hz
    seed: int = 0
    amplitude: float = 0.4  # thrust amplitude [N] of the closed-loop references
    period: float = 1.5  # [s]
    chirp_volts: float = 3.0
    noise_omega: float = 0.1  # rad/s
    noise_current: float = 0.005  # A
    noise_thrust: float = 0.004  # N
    q_theta: float = 2 * math.pi / 16384  # 14-bit encoder
    q_current: float = 1e-3  # A
    q_thrust: float = 5e-4  # N
    q_voltage: float = 12.0 / 2048  # V per count


def _reference(kind: str, t: np.ndarray, spec: RigSpec, c_f: float) -> np.ndarray:
    s = np.sin(2 * math.pi * t / spec.period)
    x2 = spec.amplitude * (s if kind == "sine" else s**5)
    return np.sign(x2) * np.sqrt(np.abs(x2) / c_f)


def _chirp(t: np.ndarray, spec: RigSpec) -> np.ndarray:
    f0, f1 = 0.3, 4.0
    phase = 2 * math.pi * (f0 * t + 0.5 * (f1 - f0) * t**2 / spec.seconds)
    return spec.chirp_volts * np.sin(phase)


def generate(params: MotorParams, spec: RigSpec = RigSpec()) -> Log:
    """Run the hidden rig and return what its logger records (SI)."""
    plant = DCMotorPlant(params, effects_from_mapping(dict(spec.effects)))
    rng = np.random.default_rng(spec.seed)
    dt = 1.0 / spec.rate
    nx = len(plant.state_names)
    xs = ca.SX.sym("x", nx)
    us = ca.SX.sym("u")
    step = ca.Function("step", [xs, us], [ca.vertcat(*rk4(plant, [xs[m] for m in range(nx)], us, dt, 20, CASADI))])
    n_seg = round(spec.seconds * spec.rate)
    tt = np.arange(n_seg) * dt
    x = np.zeros(nx)
    states, volts = [], []
    p = params
    for kind in spec.excitations:
        integ = 0.0
        w_ref = _reference(kind, tt, spec, p.c_f) if kind != "chirp" else None
        for k in range(n_seg):
            if w_ref is None:
                v = _chirp(tt[k : k + 1], spec)[0]
            else:
                w_meas = x[0] + spec.noise_omega * rng.standard_normal()
                e = w_ref[k] - w_meas
                integ += e * dt
                wd = w_ref[k]
                ff = p.k_e * wd + p.R / p.k_t * (p.B * wd + p.c_tau * wd * abs(wd))
                v = ff + 0.1 * e + 1.0 * integ
            v = float(np.clip(np.round(v / spec.q_voltage) * spec.q_voltage, -12.0, 12.0))
            states.append(x.copy())
            volts.append(v)
            x = np.asarray(step(x, v)).ravel()
    xa = np.array(states).T
    n = xa.shape[1]
    t = np.arange(n) * dt
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (xa[0, 1:] + xa[0, :-1]) * dt)])

    def q(y: np.ndarray, step_: float) -> np.ndarray:
        return np.round(y / step_) * step_

    thrust = np.asarray(plant.thrust(list(xa)), float)
    cur = np.asarray(measured_current(plant, xa[1]), float)
    return log_from_arrays(
        t, np.array(volts),
        q(cur + spec.noise_current * rng.standard_normal(n), spec.q_current),
        q(thrust + spec.noise_thrust * rng.standard_normal(n), spec.q_thrust),
        omega=xa[0] + spec.noise_omega * rng.standard_normal(n),
        theta=q(theta, spec.q_theta),
        source="synthetic-rig",
    )


def rig_summary(log: Log) -> dict[str, Any]:
    """Peak values, for eyeballing a generated log."""
    return {k: float(np.max(np.abs(v))) for k, v in log.columns().items()}
