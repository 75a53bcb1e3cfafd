"""Problem -> the flat program's answer: where it applies, its data, its solve and the verified answer.

:func:`applies` says why the flat program (:mod:`ocp.optimize.flat`) cannot serve a problem (``None``: it can);
:func:`solve_flat` resolves the mission's limits into scaled bounds and parameters, solves the cached program
from the static inverse, and returns the same :class:`~ocp.optimize.result.OptimizeResult` as the Radau
program (reference, command, fine arrays, verification), or :class:`~ocp.optimize.result.Unsolved` with the
reason; :mod:`ocp.optimize.solve` then falls back to the Radau program.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from functools import cached_property
from typing import cast

import numpy as np
from scipy.interpolate import BSpline

from ocp.model.equilibrium import equilibrium, speed_for_thrust
from ocp.model.plant import DCMotorPlant
from ocp.optimize import bspline, flat
from ocp.optimize.collocation import SolveContext
from ocp.optimize.data import WEIGHTS
from ocp.optimize.mission import output_grid
from ocp.optimize.problem import Problem, Scales, chain_order, crossing_order, scales
from ocp.optimize.result import Crossing, OptimizeResult, SolverProgram, SolverStats, Status, Unsolved
from ocp.optimize.solution import package
from ocp.simulate.zoh import union_sorted

#: the smooth voltage is held on pieces (of at least 1/SUBSTEPS of the 1 kHz output step) over which it moves by
#: about COMMAND_DV of its limit (:func:`held_command`): the response's current stays within ~COMMAND_DV V/R of
#: the plan, and a hold is one piece (a replay of the command meets few discontinuities)
COMMAND_DV, SUBSTEPS = 2e-3, 4
SPANS_PER_INTERVALS = 3  # one B-spline span per this many Radau intervals of a phase ...
SPANS = (8, 20)  # ... between these (per phase)
#: a corner of the desired thrust inside a phase (its slope between neighbouring samples jumps by more than
#: CORNER of the phase's largest slope: a ramp's ends, a coarsely sampled profile) doubles the spans, up to
#: SPANS_CORNER (a C^4 spline on 20 spans rounds the corner off: the classic ramp's objective 4.6x the Radau
#: program's; 30 spans 2.1x, 32 spans 1.35x, 34-48 spans 0.30-0.99x)
CORNER, SPANS_CORNER = 0.25, 40
NO_CONTEXT = SolveContext()
DERIVED = 2  # highest derivative of the speed a plan evaluates
#: the initial guess changes the speed at most at this fraction of the rate the current limit allows (:func:`_guess`)
GUESS_CURRENT = 0.6
ROUNDS = 2  # back-off rounds of the flat program before the Radau program is asked


def applies(problem: Problem) -> str | None:
    """Why the flat program cannot serve ``problem`` (``None``: it can): it needs the nominal voltage-driven
    DC motor (no effects: a delay, a deadband or a stateful effect has no explicit flat inverse here), a
    tracking objective and no voltage slew limit."""
    m, plant = problem.mission, problem.plant
    if m.objective != "track":
        return "min-time missions use the Radau program (mesh refinement)"
    if not (plant.voltage_driven and plant.is_nominal and isinstance(plant, DCMotorPlant)):
        return "the flat inverse is written for the plain voltage-driven DC motor"
    if m.limits.voltage_rate is not None:
        return "a voltage slew limit is kept by the Radau program"
    return None


def structure_of(problem: Problem) -> flat.FlatStructure:
    """The flat structure of ``problem``: its phases, spans per phase (from the Radau intervals, doubled up to
    :data:`SPANS_CORNER` when the desired thrust has a corner inside a phase), chain, order."""
    st = problem.structure
    spans = int(np.clip(math.ceil(st.intervals / SPANS_PER_INTERVALS), *SPANS))
    if has_corner(problem):
        spans = max(spans, min(2 * spans, SPANS_CORNER))
    return flat.FlatStructure(n_phases=st.n_phases, spans=spans, chain=chain_order(problem.mission),
                              order6=crossing_order(problem.mission) == 6)


def has_corner(problem: Problem) -> bool:
    """Whether the desired thrust (linear between its samples) turns sharply inside a phase: between two
    neighbouring sample intervals its slope [N/s] changes by more than :data:`CORNER` times the phase's largest
    slope (a smooth profile sampled at ``dt`` changes by about ``omega dt`` of it)."""
    t, f, edges = problem.t_desired, problem.f_desired, problem.phases.bounds
    for j in range(len(edges) - 1):
        inside = (t >= edges[j]) & (t <= edges[j + 1])
        slope = np.diff(f[inside]) / np.diff(t[inside])  # (M_phase - 1,)
        top = float(np.max(np.abs(slope), initial=0.0))
        if top > 0.0 and slope.size > 1 and float(np.max(np.abs(np.diff(slope)))) > CORNER * top:
            return True
    return False


@dataclass(frozen=True)
class FlatData:
    """One solve's data (scaled): parameters ``p``, bounds ``lbx``/``ubx`` and guess ``x0`` (n_x,), the scales,
    the initial state ``x_start`` (omega [rad/s], current [A])."""

    p: np.ndarray
    lbx: np.ndarray
    ubx: np.ndarray
    x0: np.ndarray
    scales: Scales
    x_start: np.ndarray


def flat_data(problem: Problem, prog: flat.FlatProgram) -> FlatData | None:
    """Parameters, bounds and the static-inverse guess; ``None`` when the initial thrust breaks a limit (the
    Radau path reports it)."""
    m, plant, st = problem.mission, cast(DCMotorPlant, problem.plant), prog.structure
    mp, lim, dur = m.motor(), m.limits, problem.phases.durations
    x_start, u0 = equilibrium(plant, speed_for_thrust(plant, float(problem.f_desired[0]), mp.c_f))
    if abs(u0) > lim.voltage or abs(x_start[1]) > lim.current:
        return None
    w_full = math.sqrt(max(float(np.max(np.abs(problem.f_desired))), 1e-6) / mp.c_f)
    sc = scales(problem, equilibrium(plant, w_full)[0])
    pts = flat.points(st.spans)
    fd = np.array([np.interp(problem.phases.bounds[j] + pts["quad"] * dur[j], problem.t_desired, problem.f_desired)
                   for j in range(st.n_phases)]) / sc.f  # (P, nq)
    p = prog.pack(constants=np.array([getattr(mp, k) for k in flat.CONSTANTS], float),
                  scales=np.array([sc.x[0], sc.f, lim.current, lim.voltage, sc.u], float),
                  sigma=problem.phases.signs, dur=dur, fd=fd, weights=WEIGHTS[m.objective],
                  intervals=problem.structure.intervals, obj_scale=1.0)
    lbx, ubx = _bounds(problem, st, sc.x[0], x_start[0])
    x0 = _guess(problem, st, fd * sc.f / mp.c_f, sc.x[0], lbx, ubx)
    return FlatData(p=flat.objective_scaled(prog, p, x0), lbx=lbx, ubx=ubx, x0=x0, scales=sc, x_start=x_start)


def _bounds(problem: Problem, st: flat.FlatStructure, ws: float, w0: float) -> tuple[np.ndarray, np.ndarray]:
    """Stretch bounds, then per phase the coefficient bounds (sign, speed limit, start, reversal), scaled."""
    m, P, nc = problem.mission, st.n_phases, st.n_coef
    w_max = (m.limits.speed if m.limits.speed is not None else np.inf) / ws
    lo = np.where(problem.phases.signs > 0, 0.0, -w_max)
    hi = np.where(problem.phases.signs > 0, w_max, 0.0)
    lbc, ubc = np.repeat(lo[:, None], nc, axis=1), np.repeat(hi[:, None], nc, axis=1)  # (P, nc)
    # start at the equilibrium: omega(0) = w0 and its first 1 + chain derivatives zero
    lbc[0, : 2 + st.chain] = ubc[0, : 2 + st.chain] = w0 / ws
    # reversal: omega = 0 (order 6: with omega' and omega'') at both sides of each boundary
    zero = 3 if st.order6 else 1
    lbc[:-1, nc - zero:] = ubc[:-1, nc - zero:] = 0.0
    lbc[1:, :zero] = ubc[1:, :zero] = 0.0
    lbx = np.concatenate([np.full(P, m.retiming.min_stretch), lbc.ravel()])
    ubx = np.concatenate([np.full(P, m.retiming.max_stretch), ubc.ravel()])
    return lbx, ubx


def _guess(problem: Problem, st: flat.FlatStructure, w2: np.ndarray, ws: float, lbx: np.ndarray,
           ubx: np.ndarray) -> np.ndarray:
    """Static inverse within the current limit: per phase the least-squares spline through the speed
    sqrt(|F_d| / c_f) (``w2`` (P, nq): desired thrust / c_f [rad^2/s^2] at the Gauss points) slowed where it
    changes faster than the current limit allows (:func:`_rate_limited`), with its sign; stretch
    1; clipped into the bounds. A start inside the current limit spares IPOPT the iterations that only reach it
    (6 to 8 of 20 to 28 on the user missions from the plain static inverse)."""
    quad = flat.quad_basis(st.spans)
    speed = np.array([_rate_limited(problem, np.sqrt(np.abs(w2[j])), j) for j in range(st.n_phases)])
    coef = np.linalg.lstsq(quad, (problem.phases.signs[:, None] * speed / ws).T, rcond=None)[0].T  # (P, nc)
    return np.clip(np.concatenate([np.ones(st.n_phases), coef.ravel()]), lbx, ubx)


def _rate_limited(problem: Problem, speed: np.ndarray, j: int) -> np.ndarray:
    """|omega| (nq,) [rad/s] at phase ``j``'s Gauss points, lowered so that it changes at most GUESS_CURRENT of the
    rate the current limit allows (rising: against the drag, falling: with it; so the current stays inside the
    limit wherever the drag alone is), and is zero at the phase's reversals (a forward and a backward pass)."""
    mp, phases = problem.mission.motor(), problem.phases
    torque = mp.k_t * problem.mission.limits.current  # [N m]
    J, B, c_tau = mp.J, mp.B, mp.c_tau
    t = (phases.bounds[j] + flat.points(speed.size // flat.GAUSS)["quad"] * phases.durations[j]).tolist()  # [s]
    # Python floats: the same IEEE operations as on numpy scalars (``**`` is C's pow in both), at a fifth of the cost
    out = speed.tolist()
    prev_t, prev = (float(phases.bounds[j]), 0.0) if j > 0 else (t[0], out[0])
    for n in range(len(out)):
        # eq:dc_mechanical  J |w|' = k_t |i| - B |w| - c_tau w^2 (speeding up)
        rate = GUESS_CURRENT * max(torque - B * prev - c_tau * prev**2, 0.0) / J
        prev = out[n] = min(out[n], prev + rate * (t[n] - prev_t))
        prev_t = t[n]
    nxt_t, nxt = (t[-1], out[-1]) if j == phases.signs.size - 1 else (float(phases.bounds[j + 1]), 0.0)
    for n in range(len(out) - 1, -1, -1):
        # eq:dc_mechanical  J |w|' = -(k_t |i| + B |w| + c_tau w^2) (slowing down)
        rate = GUESS_CURRENT * (torque + B * nxt + c_tau * nxt**2) / J
        nxt = out[n] = min(out[n], nxt + rate * (nxt_t - t[n]))
        nxt_t = t[n]
    return np.array(out)


def solve_flat(problem: Problem, context: SolveContext = NO_CONTEXT,
               warm: bool | None = False) -> OptimizeResult | Unsolved:
    """The flat program's verified answer to ``problem`` (:func:`applies` must be ``None``), or why not.

    ``warm``: the first round starts from the cached program's last solve never (``False``: from the static
    inverse), when it is plausibly close (``None``) or always (``True``) (:func:`ocp.optimize.flat.solve`).
    When the simulated response exceeds the current or the voltage limit, that channel's bound at the check
    points is backed off by the excess (plus 20 %) and the program solved again from its answer, at most
    :data:`ROUNDS` times; the caller falls back to the Radau program when it still does."""
    st = structure_of(problem)
    prog, build_s = flat.program_for(st, context.on_build)
    data = flat_data(problem, prog)
    if data is None:
        return Unsolved("the initial thrust needs more than the limits")
    m = problem.mission
    until = min(time.perf_counter() + m.time_limit_s, context.deadline)
    bound = np.full(2, 1.0 - flat.MARGIN)  # current, voltage at the check points (fractions of the limits)
    x0, info = data.x0, SolverStats(build_time_s=build_s, program=SolverProgram.FLAT)
    for rounds in range(ROUNDS + 1):
        first = warm if rounds == 0 else False
        run = flat.solve(prog, data.p, data.lbx, data.ubx, x0, prog.g_bounds(*bound), until, first)
        _add_run(info, run, rounds, float(np.min(bound) / (1.0 - flat.MARGIN)))
        if not run.success:
            return Unsolved(f"flat program: IPOPT {run.status}", info)
        t0 = time.perf_counter()
        result = _answer(problem, st, run.x, data, info)
        info.verify_time_s += time.perf_counter() - t0
        if result.path_ok:
            return result
        ratios = problem.plant.limit_ratios(result.fine, m.bounds())
        excess = np.array([np.max(ratios["limits.current"]), np.max(ratios["limits.voltage"])])
        if not np.all(np.isfinite(excess)):
            return Unsolved("flat program: the simulated response diverged", info)
        bound = np.where(excess > 1.0, bound / (1.0 + 1.2 * (excess - 1.0)), bound)
        # a back-off round starts the cold solver from this round's primal: IPOPT's warm start (duals, small
        # mu_init) took more iterations there, its active rows now infeasible (ramp, bounds 0.995 -> 0.965:
        # 32 warm, 29 cold from the static inverse, 23 from the primal)
        x0 = run.x
    return Unsolved(f"flat program: a limit is exceeded between the check points after {ROUNDS} back-off rounds",
                    info)


def _add_run(info: SolverStats, run: flat.col.Solved, rounds: int, backoff: float) -> None:
    """Fold one solve into the answer's report (times and iterations add up over the rounds)."""
    info.status, info.method, info.compiled = Status.parse(run.status), run.method, run.compiled
    info.iterations += run.iterations
    info.solve_time_s += run.solve_time_s
    info.objective, info.constraint_violation = run.objective, run.constraint_violation
    info.backoff_rounds, info.limit_backoff = rounds, backoff
    if rounds == 0:
        info.warm_start = run.warm


@dataclass(frozen=True)
class FlatPlan:
    """A solved flat program as functions of time: per phase the speed spline's coefficients ``coef`` (P, n_coef)
    [rad/s] on the knots ``knots`` of the normalised time (:func:`ocp.optimize.flat.knots`, degree
    :data:`~ocp.optimize.flat.DEGREE`), the phase edges [s] (P+1,), the speed signs (P,) and the plant constants."""

    coef: np.ndarray
    knots: np.ndarray
    phase_edges: np.ndarray
    signs: np.ndarray
    constants: dict[str, float]

    def derivatives(self, t: np.ndarray, upto: int = 2) -> tuple[list[np.ndarray], np.ndarray]:
        """(omega and its first ``upto`` (<= DERIVED) time derivatives at ``t`` (M,), each (M,); the speed sign
        (M,)). The values of scipy's ``BSpline`` and its ``derivative()`` at the phase's normalised time, over the
        phase length to the power of the order, bit for bit (:mod:`ocp.optimize.bspline`: one vectorised de Boor
        pass over every phase and order)."""
        P = self.coef.shape[0]
        j = np.clip(np.searchsorted(self.phase_edges, t, side="right") - 1, 0, P - 1)
        h = np.diff(self.phase_edges)
        tau = np.clip((t - self.phase_edges[j]) / h[j], 0.0, 1.0)
        kn = bspline.knots(self.knots, flat.DEGREE)
        ell, funcs = bspline.basis(kn, tau, flat.DEGREE - upto)
        out = []
        for r in range(upto + 1):
            per_phase = np.array([h[k] ** r for k in range(P)])  # the divisor of a scalar spline's value, per phase
            out.append(bspline.combine(kn, ell, funcs[r], self._windows[r], j) / per_phase[j])
        return out, self.signs[j]

    @cached_property
    def _windows(self) -> list[np.ndarray]:
        """Per order 0..DERIVED the coefficients of every phase's speed spline differentiated that often in tau (as
        scipy's ``BSpline.derivative``, order by order), as :func:`ocp.optimize.bspline.windows`."""
        n = self.coef.shape[1]
        chain = [BSpline(self.knots, self.coef.T, flat.DEGREE)]  # column p: phase p (splder works per column)
        for _ in range(DERIVED):
            chain.append(chain[-1].derivative())
        return [bspline.windows(np.asarray(s.c)[:n].T, flat.DEGREE) for s in chain]

    def states(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(states (omega [rad/s], current [A]) shape (2, M), voltage [V] (M,)) at ``t`` (M,)."""
        w, sign = self.derivatives(t)
        cur, volts = flat.drive([*w, np.zeros_like(t)], dict(self.constants), sign, 0)
        return np.vstack([w[0], cur]), volts


def plan_of(problem: Problem, st: flat.FlatStructure, x: np.ndarray, data: FlatData) -> FlatPlan:
    """The solved flat program ``x`` (n_x,) as functions of time (SI)."""
    P, nc = st.n_phases, st.n_coef
    mp = problem.mission.motor()
    h = x[:P] * problem.phases.durations
    coef = x[P:].reshape(P, nc) * data.scales.x[0]
    return FlatPlan(coef=coef, knots=flat.knots(st.spans), phase_edges=np.concatenate([[0.0], np.cumsum(h)]),
                    signs=problem.phases.signs, constants={k: float(getattr(mp, k)) for k in flat.CONSTANTS})


def _answer(problem: Problem, st: flat.FlatStructure, x: np.ndarray, data: FlatData,
            info: SolverStats) -> OptimizeResult:
    """Package the solved flat program: the smooth voltage held (:data:`COMMAND_DV`), simulated. The plan is
    evaluated once, at the command grid's midpoints, the output times and the reversals together."""
    plan = plan_of(problem, st, x, data)
    edges = plan.phase_edges
    t = output_grid(float(edges[-1]))
    grid = command_grid(t, edges)
    mid, ts = 0.5 * (grid[:-1] + grid[1:]), edges[1:-1]
    states, volts = plan.states(np.concatenate([mid, t, ts]))
    a, b = mid.size, mid.size + t.size
    command = held_command(grid, volts[:a], edges, COMMAND_DV * data.scales.u_lim)
    crossings = _crossings(ts, states[:, b:], volts[b:], data)
    return package(problem, t, (states[:, a:b], volts[a:b]), edges, command, data.x_start, crossings, info)


def command_grid(t: np.ndarray, phase_edges: np.ndarray) -> np.ndarray:
    """SUBSTEPS equal pieces per output step of ``t`` (M,) [s], and the phase edges (P+1,): shape (G,) [s]."""
    frac = np.arange(SUBSTEPS) / SUBSTEPS
    return union_sorted(np.append((t[:-1, None] + frac[None, :] * np.diff(t)[:, None]).ravel(), t[-1]), phase_edges)


def held_command(grid: np.ndarray, v: np.ndarray, phase_edges: np.ndarray, dv: float) -> tuple[np.ndarray, np.ndarray]:
    """The plan's smooth voltage ``v`` (G-1,) [V] at the midpoints of the pieces of ``grid`` (G,) [s]
    (:func:`command_grid`) as a held command: (knots (K+1,) [s], values (K,) [V]). A held piece ends where the
    voltage moves to another multiple of ``dv`` [V] (rounded), or at a phase edge (``phase_edges`` (P+1,) [s]);
    each holds the voltage's mean over it. A hold needs one piece, a reversal as many as its voltage's variation
    over ``dv``."""
    dt = np.diff(grid)
    level = np.round(v / dv)
    cut = np.flatnonzero(np.diff(level) != 0) + 1  # a piece starts at these grid steps
    at_edges = np.searchsorted(grid, phase_edges[1:-1])
    starts = np.union1d(np.concatenate([[0], cut, at_edges]), []).astype(int)
    held = np.add.reduceat(v * dt, starts) / np.add.reduceat(dt, starts)
    return np.append(grid[starts], grid[-1]), held


def _crossings(ts: np.ndarray, x: np.ndarray, v: np.ndarray, data: FlatData) -> list[Crossing]:
    """Local exponent at each reversal ``ts`` (R,) [s]: 2 + 2n with n the leading links of (current, voltage) that
    vanish (below 1e-6 of their limits) just after the crossing; with the planned current and voltage there
    (``x`` (2, R) the plan's states at ``ts``, i.e. at tau = 0 of the next phase, ``v`` (R,) its voltage)."""
    out = []
    scale = np.array([data.scales.x[1], data.scales.u_lim])  # the current and voltage limits [A], [V]
    for k in range(ts.size):
        links = np.abs([x[1, k], v[k]]) / scale
        n = 0
        while n < 2 and links[n] <= 1e-6:
            n += 1
        out.append(Crossing(t=float(ts[k]), exponent=float(2 * n + 2), sign_change=True, current=float(x[1, k]),
                            voltage=float(v[k])))
    return out
