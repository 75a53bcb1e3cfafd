"""Mission -> optimised reference: problem, data, the cached program's solve, back-off, answer.

``optimize(mission)`` never raises for a numerical failure: when IPOPT fails, times out, or the
mission's limits cannot be met, it returns the analytic fallback (``source="analytic-fallback"``,
:func:`ocp.reference.fallback_answer.analytic_fallback`, entered from :func:`optimize_mesh` only) with the
reason. Bad missions raise :class:`~ocp.errors.MissionError` naming the field.

The steps, one module each: :mod:`~ocp.optimize.problem` (phases, plant, structure, scales),
:mod:`~ocp.optimize.data` (parameters, bounds, initial guess), :mod:`~ocp.optimize.collocation` (the cached
program, its solve), :mod:`~ocp.optimize.solution` (evaluation and packaging), :mod:`~ocp.optimize.verify`
(simulation and limit check), :mod:`~ocp.optimize.min_time` (mesh refinement of a min-time answer).
"""

from __future__ import annotations

import dataclasses
import math
import time

import numpy as np

from ocp.errors import MissionError
from ocp.optimize import collocation as col
from ocp.optimize import flat_solve, min_time
from ocp.optimize.collocation import SolveContext
from ocp.optimize.data import ProblemData, problem_data
from ocp.optimize.guess import fastest_analytic
from ocp.optimize.mission import Mission
from ocp.optimize.problem import Problem, problem_for
from ocp.optimize.result import OptimizeResult, SolverProgram, SolverStats, Status, Unsolved
from ocp.optimize.solution import finish_result
from ocp.reference.fallback_answer import analytic_fallback

MAX_REFINEMENTS = 3  # back-off rounds when the simulated response exceeds a limit between nodes
NO_CONTEXT = SolveContext()


def optimize(mission: Mission, warm: bool | None = False, context: SolveContext = NO_CONTEXT,
             program: SolverProgram | None = None) -> OptimizeResult:
    """Optimised reference for ``mission`` (or the analytic fallback with the reason).

    ``warm``: start from the cached program's last solution (primal and dual) never (``False``, the default:
    cold, from the static inverse), when it is plausibly close (``None``: what the service's workers ask, so
    batch items and repeated requests of one structure start warm, :mod:`ocp.optimize.warm`), or always when
    its size fits (``True``).

    A min-time mission is solved on successively doubled meshes until its duration converges
    (:func:`ocp.optimize.min_time.refine`); any other mission on its own mesh (:func:`optimize_mesh`).
    ``context``: a caller's deadline and build observer (:class:`~ocp.optimize.collocation.SolveContext`);
    ``program``: which program answers (:func:`optimize_mesh`; default the flat one where it applies).
    """
    # --- min-time mesh refinement (issue 15) ---
    if mission.objective == "min-time":
        fastest = fastest_analytic(mission)
        return min_time.refine(mission, lambda m, previous: optimize_mesh(m, warm, previous, context),
                               None if fastest is None else 0.5 * fastest.period, _mesh_size)
    return optimize_mesh(mission, warm, context=context, program=program)


def _mesh_size(mission: Mission) -> int:
    """Collocation intervals a solve of ``mission`` uses over all its phases."""
    st = problem_for(mission).structure
    return st.intervals * st.n_phases


def optimize_mesh(mission: Mission, warm: bool | None = False, previous: OptimizeResult | None = None,
                  context: SolveContext = NO_CONTEXT, program: SolverProgram | None = None) -> OptimizeResult:
    """Optimised reference for ``mission`` on its own mesh (or the analytic fallback with the reason);
    ``previous``: a coarser answer of the same mission to start from (min-time refinement).

    ``program``: ``None`` (the default) asks the flat program first where it applies
    (:func:`ocp.optimize.flat_solve.applies`; not on a min-time refinement) and the Radau program when the flat
    one fails or its verified answer breaks a limit; ``radau`` asks the Radau program only (the reference, in
    benchmarks and tests); ``flat`` the flat program only (its failure goes to the analytic fallback).

    When the simulated response exceeds a limit between collocation nodes, the current and voltage
    bounds of the intervals where it does (and of their neighbours) are backed off by the excess (plus
    20 %) and the same cached program is solved again, warm-started (min-time: from the analytic guess).
    """
    started = time.perf_counter()
    outcome = _flat_or_radau(mission, warm, previous, context, started, program)
    if isinstance(outcome, Unsolved):  # the one entry into the fallback
        result = analytic_fallback(mission, outcome.reason, outcome.solver)
    else:
        result = outcome
    result.total_time_s = time.perf_counter() - started
    return result


def _flat_or_radau(mission: Mission, warm: bool | None, previous: OptimizeResult | None, context: SolveContext,
                   started: float, program: SolverProgram | None) -> OptimizeResult | Unsolved:
    """The flat program's answer where it applies and verifies, else the Radau program's (see
    :func:`optimize_mesh`); the time of a flat attempt that did not answer is reported with the Radau answer."""
    problem = problem_for(mission)
    if program == SolverProgram.RADAU or previous is not None or flat_solve.applies(problem) is not None:
        if program == SolverProgram.FLAT:
            return Unsolved(f"flat program: {flat_solve.applies(problem) or 'not on a min-time refinement'}")
        return _optimize_mesh(problem, warm, previous, context, started)
    answer = flat_solve.solve_flat(problem, context, warm)
    if isinstance(answer, OptimizeResult) or program == SolverProgram.FLAT:
        answer.solver.setup_time_s = time.perf_counter() - started - _spent(answer.solver)
        return answer
    if answer.solver.status.stopped_by_time:  # the mission's time (or the caller's) is spent
        return Unsolved("solver time limit reached", answer.solver)
    attempt = time.perf_counter() - started
    # the Radau program gets what is left of the mission's time limit
    left = dataclasses.replace(context, deadline=min(context.deadline, started + mission.time_limit_s))
    result = _optimize_mesh(problem, warm, previous, left, time.perf_counter())
    result.solver.flat_attempt_s = attempt
    return result


def _spent(s: SolverStats) -> float:
    return s.build_time_s + s.solve_time_s + s.verify_time_s


def _optimize_mesh(problem: Problem, warm: bool | None, previous: OptimizeResult | None, context: SolveContext,
                   started: float) -> OptimizeResult | Unsolved:
    mission = problem.mission
    try:
        data = problem_data(problem)
    except MissionError as exc:
        if not exc.field.startswith("limits"):
            raise
        return Unsolved(f"limits cannot be met: {exc}")
    if previous is not None:  # min-time refinement: start from the coarser mesh's answer
        data = dataclasses.replace(data, x0=min_time.mesh_guess(problem, data, previous))
    setup = time.perf_counter() - started
    result = solve_problem(problem, data, False if previous is not None else warm, context=context)
    first = result.solver
    backoff, rounds = np.ones((problem.structure.n_phases, problem.structure.intervals)), 0
    for _ in range(MAX_REFINEMENTS):
        if isinstance(result, Unsolved) or result.path_ok:
            break
        excess = _interval_excess(problem, result)
        if not np.all(np.isfinite(excess)):  # a diverged simulation says nothing about how far to back off
            break
        over = excess > 1.0
        backoff[over] /= 1.0 + 1.2 * (excess[over] - 1.0)
        data = problem_data(problem, backoff)
        # a min-time round restarts from the analytic guess: warm, it kept a worse local optimum
        # (51.47 vs 51.29 ms on the continuous-voltage reversal at 960 intervals); every back-off
        # round shares the mission's time limit
        left = max(mission.time_limit_s - first.solve_time_s, 1e-3)
        result = solve_problem(problem, data, warm=mission.objective != "min-time", time_limit=left, context=context)
        rounds += 1
        # the report covers every round: times and iterations add up; the warm solver is built on its first use
        s = result.solver
        first.build_time_s += s.build_time_s
        first.solve_time_s += s.solve_time_s
        first.verify_time_s += s.verify_time_s
        first.iterations += s.iterations
        first.status, first.objective, first.constraint_violation = s.status, s.objective, s.constraint_violation
    first.setup_time_s, first.backoff_rounds = setup, rounds
    first.limit_backoff, first.backoff_intervals = float(np.min(backoff)), int(np.sum(backoff < 1.0))
    result.solver = first
    if isinstance(result, OptimizeResult) and not result.path_ok:
        diverged = not math.isfinite(result.verification.max_abs_current + result.verification.max_abs_voltage)
        reason = ("the simulated response to the optimised command is not finite" if diverged else
                  f"the optimised response exceeds a limit between nodes after {rounds} back-off rounds")
        return Unsolved(reason, result.solver)
    return result


def _interval_excess(problem: Problem, result: OptimizeResult) -> np.ndarray:
    """Largest of |current|/limit and |voltage|/limit (for the torque channel |torque|/limit) of the
    simulated response (on its integration grid) on each collocation interval and its two neighbours (a
    node bounds the polynomials on both sides), shape (P, N)."""
    P, N = problem.structure.n_phases, problem.structure.intervals
    arr = result.fine
    phase_edges = np.concatenate([[0.0], np.cumsum(np.asarray(result.stretch) * problem.phases.durations)])
    t = arr["t"]
    j = np.clip(np.searchsorted(phase_edges, t, side="right") - 1, 0, P - 1)
    k = np.clip(((t - phase_edges[j]) / np.diff(phase_edges)[j] * N).astype(int), 0, N - 1)
    # the drive's limits the program keeps (current and voltage; the torque channel's torque)
    ratio = np.max(list(problem.plant.limit_ratios(arr, problem.mission.bounds()).values()), axis=0)
    per = np.zeros(P * N)
    np.maximum.at(per, j * N + k, ratio)
    padded = np.concatenate([[0.0], per, [0.0]])
    return np.maximum(np.maximum(padded[:-2], padded[1:-1]), padded[2:]).reshape(P, N)


def solve_problem(problem: Problem, data: ProblemData, warm: bool | None, time_limit: float | None = None,
                  context: SolveContext = NO_CONTEXT) -> OptimizeResult | Unsolved:
    """Solve the cached program; IPOPT stops after ``time_limit`` [s] of solving (default the mission's
    ``time_limit_s``; building the program is not counted, as with IPOPT's own ``max_wall_time``) or at the
    context's deadline, whichever comes first. :class:`~ocp.optimize.result.Unsolved` when IPOPT fails."""
    m = problem.mission
    build_start = time.perf_counter()
    prog = col.solver_for(problem.plant, problem.structure, col.solver_options(), context.on_build)
    build_time = time.perf_counter() - build_start
    budget = m.time_limit_s if time_limit is None else time_limit
    p = prog.pack(**data.params())
    run = prog.solve(p, data.lbx, data.ubx, data.x0, warm, min(time.perf_counter() + budget, context.deadline),
                     data.path_bound)
    status = Status.parse(run.status)
    solver_info = SolverStats(status=status, iterations=run.iterations, solve_time_s=run.solve_time_s,
                              build_time_s=build_time + run.warm_build_s, objective=run.objective,
                              constraint_violation=run.constraint_violation, warm_start=run.warm)
    if not run.success:
        return Unsolved("solver time limit reached" if status.stopped_by_time else f"IPOPT: {run.status}", solver_info)
    t0 = time.perf_counter()
    result = finish_result(problem, prog, run.x, data, solver_info)
    result.solver.verify_time_s = time.perf_counter() - t0
    return result
