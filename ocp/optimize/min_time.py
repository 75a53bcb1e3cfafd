"""Minimum-time answers that converge with the mesh: solve, double the intervals, warm-start, repeat.

A min-time solve (``objective: "min-time"``) minimises the duration: no effort term, and a smoothness
term of weight :data:`ocp.optimize.data.MIN_TIME_SMOOTHING` = 1e-10 that only conditions IPOPT (it moves the
duration by less than 1e-5 of it, within IPOPT's own precision, tested against the same solve without it),
so the optimum is the discretised minimum time. That value still depends on the mesh: a jump of the
optimal voltage (at the start, onto and off the current limit, at a reversal) takes about one collocation
interval, so the discrete minimum time falls roughly like ``c / N`` with the intervals per phase ``N``
(measured on the 2 s reversal of ``examples/reversal.json`` at 1 A / 12 V, ``continuous-voltage``: 53.08, 51.72, 51.41,
51.29 ms at 60, 120, 240, 480 intervals per phase, against 51.17 ms from an independent shooting
solve, see ``tests/test_min_time.py``).

:func:`refine` therefore solves at the mission's mesh, then at twice as many intervals, warm-started
from the coarser answer (:func:`mesh_guess`), until the last doubling changed the duration by less
than :data:`RTOL` of it, the mesh reaches :data:`~ocp.optimize.mission.MAX_INTERVALS`, or the next solve would
not fit in the mission's ``time_limit_s``. It reports the finest verified duration as ``min_time_s``
and ``min_time_error_bound_s`` = the last change: under first-order convergence ``T_N - T_inf = c/N``
the error of ``T_2N`` is exactly ``T_N - T_2N``; faster convergence makes it an over-estimate.

A fallback answer is not a minimum time: its ``min_time_s`` is ``None`` (its duration is the
mission's length) and ``min_time_note`` says why.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import numpy as np

from ocp.optimize import collocation as col
from ocp.optimize.data import ProblemData
from ocp.optimize.mission import MAX_INTERVALS, Collocation, Mission
from ocp.optimize.problem import Problem
from ocp.optimize.result import MeshStep, OptimizeResult, Source

#: stop refining when one doubling changes the minimum time by less than this share of it
RTOL = 5e-3
#: a finer mesh costs about this many times the last one (NLP twice as large, a new build)
COST_GROWTH = 2.5

#: ``solve(mission, previous)``: one mesh's answer, warm-started from ``previous`` (a coarser answer) or not
MeshSolve = Callable[[Mission, "OptimizeResult | None"], OptimizeResult]


def refine(mission: Mission, solve: MeshSolve, analytic_min_time: float | None,
           mesh_size: Callable[[Mission], int]) -> OptimizeResult:
    """The min-time answer of ``mission`` refined until it converges (see module doc).

    ``analytic_min_time`` [s] is half the period of the fastest ``A sin^(2q+1)`` within the limits (or
    None), reported beside it. ``mesh_size(mission)``: the intervals the solve really uses, over all phases (a
    phase has at least a minimum number, so the mission's own count may be less); each refinement doubles it.
    Returns the finest optimised answer with its ``verification`` extended by :func:`summary`; a fallback
    when the first mesh already fell back.
    """
    started = time.perf_counter()
    budget = float(mission.time_limit_s)
    result = solve(mission, None)
    history = [(mesh_size(mission), _duration(result))]
    note = ""
    last_cost = time.perf_counter() - started
    while result.source is Source.OPTIMIZED:
        if len(history) >= 2 and abs(history[-1][1] - history[-2][1]) <= RTOL * history[-1][1]:
            break
        intervals = 2 * history[-1][0]
        if intervals > MAX_INTERVALS:
            note = f"not converged to {RTOL:.1%}: the next mesh would exceed {MAX_INTERVALS} intervals"
            break
        elapsed = time.perf_counter() - started
        if elapsed + COST_GROWTH * last_cost > budget:
            note = (f"not converged to {RTOL:.1%}: a {intervals}-interval solve would not fit in "
                    f"time_limit_s = {budget:g} s")
            break
        t0 = time.perf_counter()
        finer = solve(mission.model_copy(update={"collocation": Collocation(intervals=intervals)}), result)
        last_cost = time.perf_counter() - t0
        if finer.source is not Source.OPTIMIZED:
            note = f"refinement stopped: the {intervals}-interval solve fell back ({finer.reason})"
            break
        result = finer
        history.append((intervals, _duration(result)))
    for name, value in summary(result, history, note, analytic_min_time).items():
        setattr(result.verification, name, value)
    result.total_time_s = time.perf_counter() - started  # every mesh
    return result


def _duration(result: OptimizeResult) -> float:
    return float(result.arrays["t"][-1] - result.arrays["t"][0])


def summary(result: OptimizeResult, history: list[tuple[int, float]], note: str,
            analytic_min_time: float | None) -> dict[str, Any]:
    """The min-time fields of ``verification``.

    ``min_time_s`` [s]: the finest verified duration (None for a fallback: its duration is the mission's
    length, not a minimum); ``min_time_error_bound_s`` [s]: the last doubling's change (None after one
    mesh); ``min_time_converged``: that change is within :data:`RTOL`; ``min_time_mesh``: every mesh
    solved, ``[{"intervals", "min_time_s"}]``; ``min_time_note``: why it is not a converged minimum ("" when
    it is); ``analytic_min_time_s``: the fastest analytic reversal within the same limits.
    """
    optimised = result.source is Source.OPTIMIZED
    bound = abs(history[-1][1] - history[-2][1]) if optimised and len(history) >= 2 else None
    converged = bound is not None and bound <= RTOL * history[-1][1]
    if not optimised:
        note = f"no minimum time: the answer is the analytic fallback ({result.reason})"
    elif bound is None and not note:
        note = "one mesh only: no error bound"
    return {"min_time_s": history[-1][1] if optimised else None,
            "min_time_error_bound_s": bound, "min_time_converged": converged,
            "min_time_mesh": [MeshStep(intervals=n, min_time_s=t) for n, t in history] if optimised else [],
            "min_time_note": note, "analytic_min_time_s": analytic_min_time}


def mesh_guess(problem: Problem, data: ProblemData, previous: OptimizeResult) -> np.ndarray:
    """Initial guess for ``problem``'s program from a coarser answer ``previous`` (scaled, clipped into the
    bounds): its phase stretches, and its simulated speed, current and input (``previous.fine``)
    interpolated at the new collocation points at the same share of each phase; states it does not
    carry (effect states) keep ``data.x0``'s guess."""
    xs = data.scales.x
    st, lay = problem.structure, col.layout(problem.structure.n_phases, problem.structure.intervals, xs.size)
    P, N, chain = st.n_phases, st.intervals, st.chain
    npx = len(problem.plant.state_names)
    guess = data.x0.copy()
    stretch = np.asarray(previous.stretch, float)
    if stretch.size != P:
        return guess
    h = stretch * problem.phases.durations
    edges = np.concatenate([[0.0], np.cumsum(h)])
    taus = ((np.arange(N)[:, None] + col.TAU[None, 1:]) / N).ravel()  # (N*DEGREE,)
    t = (edges[:-1, None] + taus[None, :] * h[:, None]).reshape(P, N, col.DEGREE)
    fine = previous.fine
    guess[lay.stretch] = stretch
    for k, name in enumerate(problem.plant.state_names):  # speed, current: what the answer carries
        if name in fine:
            guess[lay.xc[:, :, :, k]] = np.interp(t, fine["t"], fine[name]) / xs[k]
    chain_values = [fine[problem.plant.input_name]]
    for _ in range(chain):
        chain_values.append(np.gradient(chain_values[-1], fine["t"]))
    for c in range(chain):
        guess[lay.xc[:, :, :, npx + c]] = np.interp(t, fine["t"], chain_values[c]) / xs[npx + c]
    mid = (edges[:-1, None] + (np.arange(N)[None, :] + 0.5) / N * h[:, None])  # (P, N) interval middles
    guess[lay.u[:, :, 0]] = np.interp(mid, fine["t"], chain_values[chain]) / data.scales.u
    return np.clip(guess, data.lbx, data.ubx)
