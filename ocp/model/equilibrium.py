"""Equilibria of a plant: the state and input that hold a constant speed, and the speed of a thrust.

Closed form for the nominal plants; with effects, a Newton solve (scipy ``root``) of ``rhs = 0`` for
the current, the input and the effect states at fixed speed. Angle-like states (whose derivative is
the speed itself, e.g. ``cogging.theta``) cannot rest; they are set to 0.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq, root

from ocp.errors import SolverError
from ocp.model.plant import DrivenPlant, Plant, speed_from_thrust


def _angle_states(plant: Plant) -> list[int]:
    return [k for k, name in enumerate(plant.state_names) if name.endswith(".theta")]


def equilibrium(plant: DrivenPlant, omega: float) -> tuple[np.ndarray, float]:
    """(state (n_states,), input [V or rad/s^2]) holding ``omega`` [rad/s] constant."""
    nominal, u = plant.static_inverse(omega)
    if plant.is_nominal:  # the closed form is exact
        return np.array([float(s) for s in nominal]), float(u)
    n = len(plant.state_names)
    angles = _angle_states(plant)
    free = [k for k in range(1, n) if k not in angles]  # current and effect states (speed is fixed)
    x = np.zeros(n)
    x[0] = omega
    guess = np.zeros(len(free) + 1)
    for k, value in enumerate(nominal[1:], start=1):  # start from the nominal plant's equilibrium
        guess[free.index(k)] = float(value)
    guess[-1] = float(u)

    def raw(y: np.ndarray) -> np.ndarray:
        xx = x.copy()
        xx[free] = y[:-1]
        d = np.array(plant.rhs(list(xx), y[-1]), dtype=float)
        return d[[0, *free]]

    # each equation divided by its sensitivity to its own unknown: residuals in the unknowns' units
    # (the mechanical one is ~1/J = 4e4 times larger than the electrical one otherwise)
    base = raw(guess)
    sens = np.empty_like(guess)
    for k in range(guess.size):
        y = guess.copy()
        h = 1e-6 * max(1.0, abs(y[k]))
        y[k] += h
        sens[k] = max(float(np.max(np.abs(raw(y) - base))) / h, 1e-12)

    def residual(y: np.ndarray) -> np.ndarray:
        return raw(y) / sens

    sol = root(residual, guess, method="hybr")
    if not sol.success or np.max(np.abs(residual(sol.x))) > 1e-9 * (1.0 + np.max(np.abs(sol.x))):
        raise SolverError("equilibrium", f"no steady state found at omega = {omega:.4g} rad/s: {sol.message}")
    x[free] = sol.x[:-1]
    return x, float(sol.x[-1])


def speed_for_thrust(plant: DrivenPlant, thrust: float, c_f: float) -> float:
    """Steady speed [rad/s] at which ``plant`` produces ``thrust`` [N] (static inverse if nominal)."""
    w_ideal = float(speed_from_thrust(thrust, c_f))
    if plant.is_nominal:
        return w_ideal

    def gap(w: float) -> float:
        x, _ = equilibrium(plant, w)
        return float(plant.thrust(list(x))) - thrust

    span = 0.5 * abs(w_ideal) + math.sqrt(max(abs(thrust), 1e-9) / c_f) + 1.0
    lo, hi = w_ideal - span, w_ideal + span
    if gap(lo) * gap(hi) > 0:
        return w_ideal
    return float(brentq(gap, lo, hi, xtol=1e-10))
