"""The one zero-order-hold simulator: a plant under a held input, fixed-step RK4, in CasADi.

Used by the optimiser's verification (:mod:`ocp.optimize.result`), identification's free run
(:mod:`ocp.identify.predict`) and ``thrustshape simulate --hold zoh`` (:func:`ocp.simulate.open_loop.simulate_zoh`).

* **One stability rule** (:func:`step_limit`): a step of ``SUBSTEPS`` RK4 sub-steps lasts at most
  ``SUBSTEPS * RK4_STIFFNESS / |lambda|`` [s], ``lambda`` [1/s] the fastest eigenvalue of the plant's Jacobian
  at the start state and at that state with the speed set to zero (for the DC motor about ``-R/L``), and at
  most ``max_step`` [s] (accuracy of the slow modes; verification uses ``SIM_STEP``).
* **Built once per plant and shape**: the step ``(x, u, dt) -> x+`` once per plant, its ``mapaccum`` over K
  steps once per (plant, K) (:func:`accumulator`).
* **Optionally compiled** (:mod:`ocp.simulate.compiled`): the step as C, built by the C compiler found at run
  time and cached on disk; where there is none the CasADi virtual machine evaluates the same expression graph.

Array layout: states (nx, K+1) on the integration grid (K+1,), inputs (K,) held from each grid point on.
"""

from __future__ import annotations

from collections.abc import Hashable, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, cast

import casadi as ca
import numpy as np

from ocp.errors import MissionError
from ocp.model.plant import CASADI, NUMPY, Ops, Plant
from ocp.simulate import compiled

SIM_STEP = 2.5e-4  # s, longest step (SUBSTEPS RK4 sub-steps each) of the optimiser's verification
RK4_STIFFNESS = 0.32  # largest |h lambda| of an RK4 sub-step: RK4 is stable to 2.78, its error ~ (h lambda)^5 / 120
SUBSTEPS = 2  # RK4 sub-steps per step
MAX_SIM_STEPS = 2_000_000  # steps of one simulation (about a second of computing)


def rk4(plant: Plant, x: list[Any], u: Any, dt: Any, n: int, ops: Ops = NUMPY) -> list[Any]:
    """``n`` classic RK4 sub-steps of ``dt / n`` [s] under the held input ``u``: the one RK4 of the
    project, for numbers (``NUMPY``, arrays broadcast) and for CasADi expressions (``CASADI``)."""
    h = dt / n
    for _ in range(n):
        k1 = plant.rhs(x, u, ops)
        k2 = plant.rhs([a + 0.5 * h * b for a, b in zip(x, k1, strict=True)], u, ops)
        k3 = plant.rhs([a + 0.5 * h * b for a, b in zip(x, k2, strict=True)], u, ops)
        k4 = plant.rhs([a + h * b for a, b in zip(x, k3, strict=True)], u, ops)
        x = [a + h / 6.0 * (b1 + 2 * b2 + 2 * b3 + b4) for a, b1, b2, b3, b4 in zip(x, k1, k2, k3, k4, strict=True)]
    return x


@lru_cache(maxsize=16)
def _jacobian_function(plant: Any) -> ca.Function:
    """``(x, u) -> d rhs / d x`` of ``plant``, built once per plant."""
    nx = len(plant.state_names)
    x, u = ca.SX.sym("x", nx), ca.SX.sym("u")
    rhs = ca.vertcat(*plant.rhs([x[i] for i in range(nx)], u, CASADI))
    return ca.Function("rhs_jacobian", [x, u], [ca.jacobian(rhs, x)])


def fastest_rate(plant: Plant, x0: Sequence[float] | np.ndarray, u0: float) -> float:
    """Largest |eigenvalue| [1/s] of the plant's Jacobian at ``x0`` (nx,) and at ``x0`` with the speed zero."""
    return _rate(_jacobians(plant, x0, u0))


def _rate(jacs: list[np.ndarray]) -> float:
    """Largest |eigenvalue| [1/s] of the Jacobians ``jacs`` (each (nx, nx))."""
    return max(float(np.max(np.abs(np.linalg.eigvals(a)))) for a in jacs)


def _jacobians(plant: Plant, x0: Sequence[float] | np.ndarray, u0: float) -> list[np.ndarray]:
    """The plant's Jacobians (nx, nx) at ``x0`` (nx,) and at ``x0`` with the speed zero."""
    jac = _jacobian_function(cast(Hashable, plant))
    at_rest = np.array(x0, float)
    at_rest[0] = 0.0
    return [np.asarray(jac(x, u0)) for x in (np.asarray(x0, float), at_rest)]


def step_limit(plant: Plant, x0: Sequence[float] | np.ndarray, u0: float, max_step: float = SIM_STEP) -> float:
    """Longest step [s] (``SUBSTEPS`` RK4 sub-steps): each sub-step keeps ``|h lambda| <= RK4_STIFFNESS`` for the
    fastest eigenvalue (:func:`fastest_rate`; 2500 1/s for the paper rig's winding, a 20 uH winding makes it
    100x faster and a fixed step would diverge), and the step is at most ``max_step`` [s].

    No eigenvalue is larger than the Jacobian's largest absolute row sum: where even that bound (widened by 1e-8
    for rounding) allows ``max_step``, the eigenvalues are not computed (the same answer, ``max_step``)."""
    jacs = _jacobians(plant, x0, u0)
    bound = max(float(np.max(np.sum(np.abs(a), axis=1))) for a in jacs) * (1.0 + 1e-8)
    if SUBSTEPS * RK4_STIFFNESS / bound >= max_step:  # False for a NaN bound or an infinite max_step
        return max_step
    lam = _rate(jacs)
    return min(max_step, SUBSTEPS * RK4_STIFFNESS / lam) if lam > 0 else max_step


@lru_cache(maxsize=16)
def step_function(plant: Any) -> ca.Function:
    """CasADi step ``(x (nx,), u, dt [s]) -> x+`` of ``SUBSTEPS`` RK4 sub-steps, built once per plant."""
    nx = len(plant.state_names)
    x, u, dt = ca.SX.sym("x", nx), ca.SX.sym("u"), ca.SX.sym("dt")
    return ca.Function("zoh_step", [x, u, dt], [ca.vertcat(*rk4(plant, [x[i] for i in range(nx)], u, dt,
                                                                    SUBSTEPS, CASADI))])


@lru_cache(maxsize=16)
def _compiled(plant: Any) -> compiled.CompiledStep:
    return compiled.CompiledStep(step_function(plant))


@lru_cache(maxsize=64)
def _accumulator(plant: Any, steps: int) -> ca.Function:
    return step_function(plant).mapaccum("zoh", steps)


def accumulator(plant: Plant, steps: int, compile_step: bool = True) -> compiled.Driver:
    """``(x0 (nx,), u (steps,), dt (steps,)) -> states (nx, steps)`` after each step. ``compile_step``: the step
    compiled to C with a C loop over the steps (:class:`ocp.simulate.compiled.CompiledStep`; the first uses of
    a new plant start its build and run uncompiled meanwhile); else, or without a C compiler, the CasADi
    virtual machine (``mapaccum``, built once per plant and length). Both give the same numbers."""
    key = cast(Hashable, plant)
    if compile_step and compiled.enabled():
        fast = _compiled(key).get()
        if fast is not None:
            return fast
    acc = _accumulator(key, int(steps))
    return lambda x0, u, dt: np.asarray(acc(x0, np.reshape(u, (1, -1)), np.reshape(dt, (1, -1))))


def union_sorted(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.union1d(a, b)`` (the sorted distinct values of both, float64), by inserting the values of the shorter
    into the longer when both are strictly increasing (a merge: a sort of both cost 4-20x more on the
    verification's grids of 10^3-10^4 times), else by ``np.union1d``."""
    a, b = np.asarray(a, dtype=np.float64).ravel(), np.asarray(b, dtype=np.float64).ravel()
    if a.size < b.size:
        a, b = b, a
    if b.size == 0 or not (np.all(a[1:] > a[:-1]) and np.all(b[1:] > b[:-1])):
        return np.union1d(a, b)
    pos = np.searchsorted(a, b)
    new = a[np.minimum(pos, a.size - 1)] != b
    return np.insert(a, pos[new], b[new])


def fine_grid(grid: np.ndarray, step_max: float) -> np.ndarray:
    """Every interval of ``grid`` (G,) split into ``ceil(length / step_max)`` equal steps: shape (K+1,)."""
    return _fine(grid, _steps_per_interval(grid, step_max).astype(np.int64))


def _steps_per_interval(grid: np.ndarray, step_max: float) -> np.ndarray:
    """Steps of at most ``step_max`` [s] in each interval of ``grid`` (G,), at least one: shape (G-1,) (whole
    numbers as floats: an infinite count stays one, for the caller's check)."""
    return np.maximum(1, np.ceil(np.diff(grid) / step_max))


def _fine(grid: np.ndarray, n_sub: np.ndarray) -> np.ndarray:
    """``grid`` (G,) with interval g split into ``n_sub[g]`` equal steps (its first point ``grid[g]`` itself)."""
    first = np.repeat(np.cumsum(n_sub) - n_sub, n_sub)
    return np.append(np.repeat(grid[:-1], n_sub) + (np.arange(n_sub.sum()) - first) * np.repeat(np.diff(grid) / n_sub,
                                                                                                 n_sub), grid[-1])


@dataclass(frozen=True)
class Response:
    """A simulated response. Attributes: ``at_out`` states (nx, M) at the requested times; ``t`` the
    integration grid [s] (K,), ``x`` the states on it (nx, K), ``u`` the input held from each grid point
    on (K,; the last one repeated)."""

    at_out: np.ndarray
    t: np.ndarray
    x: np.ndarray
    u: np.ndarray


def simulate_held(plant: Plant, t_knots: np.ndarray, u_of_interval: np.ndarray, x0: np.ndarray,
                  t_out: np.ndarray, max_step: float = SIM_STEP, compile_step: bool = True) -> Response:
    """Integrate ``plant`` from ``x0`` (nx,) under the input held at ``u_of_interval[k]`` on
    ``[t_knots[k], t_knots[k+1])``, on a grid through the knots and ``t_out`` (M,) with steps of at most
    :func:`step_limit` (evaluated at ``x0`` and the first input).

    Raises :class:`MissionError` (``params``) when the plant is too stiff for ``MAX_SIM_STEPS`` steps.
    """
    grid = union_sorted(t_knots, t_out)
    step_max = step_limit(plant, x0, float(u_of_interval[0]), max_step)
    per = _steps_per_interval(grid, step_max)
    n_steps = int(np.sum(per))
    if n_steps > MAX_SIM_STEPS:
        raise MissionError("params", f"too stiff to verify: the plant's fastest mode needs steps of {step_max:.3g} s, "
                                     f"{n_steps} of them over {grid[-1] - grid[0]:.3g} s (at most {MAX_SIM_STEPS})")
    n_sub = per.astype(np.int64)
    fine = _fine(grid, n_sub)
    # the grid holds every knot: the steps of a grid interval share the input held from its start, and a grid
    # point (every output time) is the fine point that starts its interval's steps (or the last one)
    k = np.clip(np.searchsorted(t_knots, grid[:-1], side="right") - 1, 0, u_of_interval.size - 1)
    u = np.repeat(u_of_interval[k], n_sub)
    xs = accumulator(plant, fine.size - 1, compile_step)(np.asarray(x0, float), u, np.diff(fine))
    states = np.concatenate([np.asarray(x0, float)[:, None], xs], axis=1)
    at_grid = np.append(np.cumsum(n_sub) - n_sub, fine.size - 1)
    idx = at_grid[np.clip(np.searchsorted(grid, t_out), 0, grid.size - 1)]
    return Response(at_out=states[:, idx], t=fine, x=states, u=np.append(u, u[-1]))


def steps_per_sample(plant: Plant, dt: float, x0: Sequence[float] | np.ndarray, u0: float,
                     max_step: float = np.inf) -> int:
    """Steps of :func:`step_limit` per held sample of ``dt`` [s] (uniform samples)."""
    return max(1, int(np.ceil(dt / step_limit(plant, x0, u0, max_step))))


@lru_cache(maxsize=8)
def _segments(plant: Any, per_sample: int, length: int, n_segments: int, read: tuple[int, ...],
              workers: int) -> ca.Function:
    step = step_function(plant)
    x, u, dt = ca.SX.sym("x", len(plant.state_names)), ca.SX.sym("u", 1 + len(read)), ca.SX.sym("dt")
    xk = ca.vertcat(*[u[1 + read.index(j)] if j in read else x[j] for j in range(x.numel())]) if read else x
    for _ in range(per_sample):
        xk = step(xk, u[0], dt)  # an SX call inlines the step's expression
    sample = ca.Function("zoh_sample", [x, u, dt], [xk])
    runs = sample.mapaccum(length - 1)
    return runs.map(n_segments, "thread", workers) if workers > 1 else runs.map(n_segments)


def segment_simulator(plant: Plant, per_sample: int, length: int, n_segments: int,
                      read: tuple[int, ...] = (), workers: int = 1) -> ca.Function:
    """``(x0 (nx, B), u (1 + R, B*(length-1)), dt) -> states (nx, B*(length-1))``: ``n_segments`` runs of
    ``length`` uniform samples, each sample ``per_sample`` steps of ``dt`` [s] (the sample period / per_sample)
    under its held input ``u[0]``; the states ``read`` (R indices) are set at each sample's start to the rows
    ``u[1:]`` (states a log measures, read instead of simulated: :func:`ocp.identify.predict.free_run`). Built
    once per plant, shape and reading, in the CasADi virtual machine (a fit simulates many candidate plants once
    each, where building C would cost more than it saves). ``workers`` > 1: the segments are run by that many of
    CasADi's own threads inside the one call (each segment's arithmetic, hence its numbers, the same)."""
    return _segments(cast(Hashable, plant), int(per_sample), int(length), int(n_segments), tuple(read), int(workers))
