"""Forward simulation of a :class:`~ocp.model.plant.Plant` under a given input signal.

Array layout: time ``t`` shape (N,), input ``u`` shape (N,), states shape (n_states, N).
Two integrators:

* :func:`simulate` -- adaptive (scipy ``solve_ivp``, Radau: the electrical pole makes the DC
  plant stiff) for an input given as a callable or as samples interpolated linearly;
* :func:`simulate_zoh` -- a zero-order-held input (a sampled digital command): the project's one
  zero-order-hold simulator (:mod:`ocp.simulate.zoh`, fixed RK4 steps under its stability rule).

:func:`rk4` (the one RK4) lives in :mod:`ocp.simulate.zoh`; :func:`rk4_step` is its numpy form for one state,
the building block of closed-loop loops (:mod:`ocp.simulate.closed_loop`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.integrate import cumulative_trapezoid, solve_ivp

from ocp.errors import MissionError, SolverError
from ocp.model.plant import Plant
from ocp.simulate.zoh import SUBSTEPS, rk4, simulate_held

InputSignal = Callable[[float], float] | np.ndarray


@dataclass(frozen=True)
class Trajectory:
    """Simulated response.

    Attributes:
        t: time [s], shape (N,)
        u: input [plant unit: V or rad/s^2], shape (N,)
        x: states, shape (n_states, N), rows named by ``state_names``
        thrust: thrust [N], shape (N,)
        theta: rotor angle [rad], shape (N,), integral of omega from t[0]
    """

    t: np.ndarray
    u: np.ndarray
    x: np.ndarray
    thrust: np.ndarray
    theta: np.ndarray
    state_names: tuple[str, ...]

    def state(self, name: str) -> np.ndarray:
        return self.x[self.state_names.index(name)]


def _check_time(t: np.ndarray, name: str = "t") -> None:
    if t.ndim != 1 or t.size < 2:
        raise MissionError(name, "needs at least two samples in a 1-D array")
    if not np.all(np.isfinite(t)):
        raise MissionError(name, "contains NaN or inf")
    if np.any(np.diff(t) <= 0):
        raise MissionError(name, "must be strictly increasing")


def _finish(plant: Plant, t: np.ndarray, u: np.ndarray, x: np.ndarray) -> Trajectory:
    thrust = np.asarray(plant.thrust(list(x)), dtype=float)
    theta = cumulative_trapezoid(x[0], t, initial=0.0)
    return Trajectory(t=t, u=u, x=x, thrust=thrust, theta=theta, state_names=plant.state_names)


def simulate(
    plant: Plant,
    t: np.ndarray,
    u: InputSignal,
    x0: Sequence[float],
    rtol: float = 1e-9,
    atol: float = 1e-9,
) -> Trajectory:
    """Integrate ``plant`` from ``x0`` over the grid ``t`` (N,) under input ``u``.

    ``u`` is a callable ``u(t)`` or samples of shape (N,) on ``t``, interpolated linearly.
    """
    t = np.asarray(t, dtype=float)
    _check_time(t)
    if callable(u):
        u_of_t = u
        u_samples = np.array([u(float(tk)) for tk in t])
    else:
        u_samples = np.asarray(u, dtype=float)
        if u_samples.shape != t.shape:
            raise MissionError("u", f"shape {u_samples.shape} does not match t {t.shape}")

        def u_of_t(tt: float) -> float:
            return float(np.interp(tt, t, u_samples))

    def f(tt: float, x: np.ndarray) -> list[float]:
        return [float(v) for v in plant.rhs(list(x), u_of_t(tt))]

    sol = solve_ivp(f, (t[0], t[-1]), np.asarray(x0, float), method="Radau", t_eval=t, rtol=rtol, atol=atol)
    if not sol.success:
        raise SolverError("simulate", f"integration failed: {sol.message}")
    return _finish(plant, t, u_samples, sol.y)


def rk4_step(plant: Plant, x: np.ndarray, u: float, dt: float, substeps: int) -> np.ndarray:
    """Advance state ``x`` (n_states,) by ``dt`` [s] under constant input ``u`` with RK4 sub-steps."""
    return np.array(rk4(plant, list(x), u, dt, substeps), dtype=float)


def simulate_zoh(
    plant: Plant, t: np.ndarray, u: np.ndarray, x0: Sequence[float], max_substep: float = 1e-4
) -> Trajectory:
    """Integrate under the zero-order hold of samples ``u`` (N,) on ``t`` (N,): ``u[k]`` acts on
    ``[t[k], t[k+1])``. RK4 sub-steps are at most ``max_substep`` [s] and within the simulator's stability
    rule (:func:`ocp.simulate.zoh.step_limit`: the DC plant's electrical time constant L/R is ~0.4 ms for the
    paper rig)."""
    t = np.asarray(t, dtype=float)
    u = np.asarray(u, dtype=float)
    _check_time(t)
    if u.shape != t.shape:
        raise MissionError("u", f"shape {u.shape} does not match t {t.shape}")
    if not np.all(np.isfinite(u)):
        raise MissionError("u", "contains NaN or inf")
    x_start = np.asarray(x0, dtype=float)
    if x_start.shape != (len(plant.state_names),) or not np.all(np.isfinite(x_start)):
        raise MissionError("x0", f"needs {len(plant.state_names)} finite values ({', '.join(plant.state_names)})")
    resp = simulate_held(plant, t, u[:-1], x_start, t, max_step=SUBSTEPS * max_substep)
    return _finish(plant, t, u, resp.at_out)
