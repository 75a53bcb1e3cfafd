"""Problem -> problem data: the program's parameters, variable bounds and initial guess, as one frozen value.

:func:`problem_data` resolves the mission's limits once into scaled bounds (retiming, speed sign, current
and input limits backed off per interval, initial state, reversal conditions) and the initial guess
(:mod:`ocp.optimize.guess`); :class:`ProblemData` carries the named parameters that
:meth:`ocp.optimize.collocation.Program.pack` lays out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ocp.errors import MissionError
from ocp.model.equilibrium import equilibrium, speed_for_thrust
from ocp.model.plant import Plant
from ocp.optimize import collocation as col
from ocp.optimize import path_limits
from ocp.optimize.guess import analytic_guess, initial_guess
from ocp.optimize.problem import Problem, Scales, crossing_order, scales

#: smoothness weight of a min-time solve: conditioning only. Weight 1e-4 moved the optimum (about +0.6 ms on a
#: 51 ms reversal); 1e-10 moves it by < 1e-5 relative (tests/optimize/test_min_time.py) while keeping IPOPT's
#: Hessian regular in the slew of a continuous voltage (with 0, a solve from the static inverse stalled)
MIN_TIME_SMOOTHING = 1e-10
#: weights of (track, time, stretch, smooth, effort) per objective
WEIGHTS = {"track": (1.0, 0.0, 1e-3, 1e-6, 1e-9), "min-time": (0.0, 1.0, 0.0, MIN_TIME_SMOOTHING, 0.0)}


@dataclass(frozen=True)
class ProblemData:
    """Parameters, bounds and initial guess of one solve of a problem's program (scaled, O(1)).

    Attributes:
        fd: desired thrust at the collocation points / ``scales.f``, shape (P, N*DEGREE)
        signs: speed sign per phase, shape (P,)
        durations: desired phase durations [s], shape (P,)
        scales: the per-call scales (:class:`~ocp.optimize.problem.Scales`)
        rho: residual scaling per state, shape (nx,)
        weights: (track, time, stretch, smooth, effort) objective weights
        lbx, ubx: variable bounds, shape (n,) (``Program.layout.n``)
        x0: initial guess, shape (n,)
        path_bound: bound of |current| / limit at the program's in-interval check points
            (:func:`ocp.optimize.path_limits.path_bounds`), shape (P*N*checks,)
    """

    fd: np.ndarray
    signs: np.ndarray
    durations: np.ndarray
    scales: Scales
    rho: np.ndarray
    weights: tuple[float, ...]
    lbx: np.ndarray
    ubx: np.ndarray
    x0: np.ndarray
    path_bound: np.ndarray

    def params(self) -> dict[str, Any]:
        """The named parameters for :meth:`ocp.optimize.collocation.Program.pack`."""
        sc = self.scales
        return {"fd": self.fd, "sigma": self.signs, "dur": self.durations, "xscale": sc.x, "uscale": sc.u,
                "rho": self.rho, "fscale": sc.f, "weights": self.weights}


def _path_bounds(problem: Problem, lay: col.Layout, sc: Scales, backoff: np.ndarray,
                 lbx: np.ndarray, ubx: np.ndarray) -> None:
    """Retiming, speed sign and limit, current, input (chain) bounds, in place (scaled); ``backoff`` (P, N)
    scales the current and input bounds per interval."""
    m, chain = problem.mission, problem.structure.chain
    npx = len(problem.plant.state_names)
    lim = m.limits
    if m.objective == "track":
        lbx[lay.stretch], ubx[lay.stretch] = m.retiming.min_stretch, m.retiming.max_stretch
    else:
        lbx[lay.stretch], ubx[lay.stretch] = 1e-3, max(100.0, m.retiming.max_stretch)
    w_max = (lim.speed if lim.speed is not None else np.inf) / sc.x[0]
    bounded = problem.plant.state_limits(m.bounds())
    for j, sign in enumerate(problem.phases.signs):
        w = lay.xc[j, :, :, 0]
        lbx[w], ubx[w] = (0.0, w_max) if sign > 0 else (-w_max, 0.0)
        b = backoff[j][:, None]  # (N, 1) over the interval's points
        for k in bounded:  # scaled by its limit (ocp.optimize.problem.scales)
            lbx[lay.xc[j, :, :, k]], ubx[lay.xc[j, :, :, k]] = -b, b
        if chain >= 1:
            lbx[lay.xc[j, :, :, npx]], ubx[lay.xc[j, :, :, npx]] = -b, b
        if chain >= 2 and lim.voltage_rate is not None:
            lbx[lay.xc[j, :, :, npx + 1]], ubx[lay.xc[j, :, :, npx + 1]] = -1.0, 1.0
    if chain == 0:
        lbx[lay.u], ubx[lay.u] = -backoff[:, :, None], backoff[:, :, None]
    elif chain == 1 and lim.voltage_rate is not None:
        lbx[lay.u], ubx[lay.u] = -1.0, 1.0


def _fix(lbx: np.ndarray, ubx: np.ndarray, idx: Any, value: Any) -> None:
    lbx[idx] = ubx[idx] = value


def _boundary_conditions(problem: Problem, lay: col.Layout, sc: Scales, start: np.ndarray,
                         lbx: np.ndarray, ubx: np.ndarray) -> None:
    """Initial state, reversal conditions at phase boundaries, min-time end state, in place (scaled)."""
    m, plant = problem.mission, problem.plant
    npx, nx = len(plant.state_names), sc.x.size
    _fix(lbx, ubx, lay.x0, start / sc.x)
    # omega = 0 at every phase boundary; omega ~ s^3 also needs omega' (current) = omega'' (voltage) = 0
    vanish = [0, 1, npx] if crossing_order(m) == 6 else [0]
    if max(vanish) >= nx:
        raise MissionError("min_crossing_order", f"order {m.min_crossing_order} needs the input to be a state")
    for j in range(problem.structure.n_phases - 1):
        _fix(lbx, ubx, lay.xc[j, -1, -1, vanish], 0.0)
    if m.objective == "min-time":  # end at rest at the last level (angle-like states stay free)
        x_end, u1 = equilibrium(plant, speed_for_thrust(plant, float(problem.f_desired[-1]), m.motor().c_f))
        end = np.array([*x_end, u1, 0.0][:nx]) / sc.x
        rest = [k for k, name in enumerate(plant.state_names) if not name.endswith(".theta")] + list(range(npx, nx))
        _fix(lbx, ubx, lay.xc[-1, -1, -1, rest], end[rest])


def problem_data(problem: Problem, backoff: float | np.ndarray = 1.0,
                 analytic_start: bool = True) -> ProblemData:
    """Parameter vector, bounds and initial guess for the cached program of ``problem``.

    ``backoff`` (<= 1; a number or one per interval, (P, N)) shrinks the current and voltage bounds relative
    to the limits (at the nodes and, for the current, inside the intervals). The initial guess is the static
    inverse of the desired thrust at stretch 1, except for a
    min-time mission with reversals and ``analytic_start``: then it is the fastest analytic reversal
    (:func:`ocp.optimize.guess.analytic_guess`).
    """
    m, st, plant = problem.mission, problem.structure, problem.plant
    params, dur = m.motor(), problem.phases.durations
    P, N, chain = st.n_phases, st.intervals, st.chain
    npx = len(plant.state_names)
    x_start, u0 = equilibrium(plant, speed_for_thrust(plant, float(problem.f_desired[0]), params.c_f))
    w_full = math.sqrt(max(float(np.max(np.abs(problem.f_desired))), 1e-6) / params.c_f)
    sc = scales(problem, equilibrium(plant, w_full)[0])
    over = [abs(x_start[k]) > limit for k, limit in plant.state_limits(m.bounds()).items()]
    if abs(u0) > sc.u_lim or any(over):
        raise MissionError("limits", f"the initial thrust {problem.f_desired[0]:.4g} N needs more than the limits")
    rho = _residual_scaling(plant, sc.x, sc.u_lim, N, float(np.mean(dur)), npx, chain)
    # desired thrust at the collocation points, at the same normalised time of each desired phase
    taus = ((np.arange(N)[:, None] + col.TAU[None, 1:]) / N).ravel()  # (N*DEGREE,)
    fd = np.array([np.interp(problem.phases.bounds[j] + taus * dur[j], problem.t_desired, problem.f_desired)
                   for j in range(P)]) / sc.f  # (P, N*DEGREE)
    lay = col.layout(P, N, npx + chain)
    lbx, ubx = np.full(lay.n, -np.inf), np.full(lay.n, np.inf)
    _path_bounds(problem, lay, sc, np.broadcast_to(np.asarray(backoff, float), (P, N)), lbx, ubx)
    start = np.array([*x_start, u0, 0.0][: npx + chain])
    _boundary_conditions(problem, lay, sc, start, lbx, ubx)
    x0 = np.zeros(lay.n)
    x0[lay.stretch] = 1.0
    x0[lay.x0] = start / sc.x
    x0 = initial_guess(problem, lay, x0, fd * sc.f, sc.x, sc.u, chain, lbx, ubx)
    if analytic_start and m.objective == "min-time" and P > 1:
        x0 = analytic_guess(problem, lay, x0, sc, lbx, ubx)
    margin = 0.0 if m.objective == "min-time" else path_limits.PATH_MARGIN
    path_bound = path_limits.path_bounds(np.broadcast_to(np.asarray(backoff, float), (P, N)), margin)
    return ProblemData(fd=fd, signs=problem.phases.signs, durations=dur, scales=sc, rho=rho,
                       weights=WEIGHTS[m.objective], lbx=lbx, ubx=ubx, x0=x0, path_bound=path_bound)


def _residual_scaling(plant: Plant, xscale: np.ndarray, u_nom: float, N: int, d_nom: float, npx: int,
                      chain: int) -> np.ndarray:
    """Per-state factor min(1, tau_m N / d): tau_m from the diagonal of the plant Jacobian."""
    x = 0.5 * xscale[:npx]
    base = np.array(plant.rhs(list(x), 0.5 * u_nom), dtype=float)
    rho = np.ones(npx + chain)
    for m in range(npx):
        dx = x.copy()
        dx[m] += 1e-6 * xscale[m]
        jac = (np.array(plant.rhs(list(dx), 0.5 * u_nom), dtype=float)[m] - base[m]) / (1e-6 * xscale[m])
        if jac != 0:
            rho[m] = min(1.0, N / (abs(jac) * d_nom))
    return rho
