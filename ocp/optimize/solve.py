"""Mission -> optimised reference: phases, data for the cached collocation program, solve, verify.

``optimize(mission)`` never raises for a numerical failure: when IPOPT fails, times out, or the
mission's limits cannot be met, it returns the analytic fallback (``source="analytic-fallback"``)
with the reason. Bad missions raise :class:`~ocp.errors.MissionError` naming the field.
"""

from __future__ import annotations

import itertools
import math
import time
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ocp.errors import MissionError
from ocp.model.equilibrium import equilibrium, speed_for_thrust
from ocp.model.plant import DCMotorPlant, Plant, TorquePlant, speed_from_thrust
from ocp.optimize import collocation as col
from ocp.optimize import min_time
from ocp.optimize.mission import MAX_INTERVALS, Mission
from ocp.optimize.result import OptimizeResult, analytic_fallback, finish_result
from ocp.reference.analytic import SinProfile, reference
from ocp.reference.fallback import design_sin
from ocp.theory.crossings import sign_change_times
from ocp.theory.reversal import ReversalRegularity

#: smoothness weight of a min-time solve: conditioning only. Weight 1e-4 moved the optimum (about +0.6 ms on a
#: 51 ms reversal); 1e-10 moves it by < 1e-5 relative (tests/test_min_time.py) while keeping IPOPT's Hessian
#: regular in the slew of a continuous voltage (with 0, a solve from the static inverse stalled)
MIN_TIME_SMOOTHING = 1e-10
#: weights of (track, time, stretch, smooth, effort) per objective
WEIGHTS = {"track": (1.0, 0.0, 1e-3, 1e-6, 1e-9), "min-time": (0.0, 1.0, 0.0, MIN_TIME_SMOOTHING, 0.0)}
MIN_INTERVALS_PER_PHASE = (8, 30)  # piecewise-constant input, input as a state
MAX_REFINEMENTS = 3  # back-off rounds when the simulated response exceeds a limit between nodes


@dataclass(frozen=True)
class Phases:
    """Desired profile split at its reversals.

    Attributes:
        bounds: phase boundaries in desired time [s], shape (P+1,)
        signs: speed sign per phase (+1/-1), shape (P,)
    """

    bounds: np.ndarray
    signs: np.ndarray

    @property
    def durations(self) -> np.ndarray:
        return np.diff(self.bounds)


def split_phases(t: np.ndarray, f: np.ndarray) -> Phases:
    """Phases between sign changes of the desired thrust ``f`` (N,) on ``t`` (N,)."""
    cuts = sign_change_times(t, f, 1e-12 * float(np.max(np.abs(f))))
    bounds = np.array([t[0], *cuts, t[-1]])
    signs = []
    for a, b in itertools.pairwise(bounds):
        inside = f[(t > a) & (t < b)]
        s = np.sign(np.sum(np.sign(inside))) if inside.size else np.sign(np.interp(0.5 * (a + b), t, f))
        signs.append(1.0 if s >= 0 else -1.0)
    if np.any(np.diff(bounds) <= 0):
        raise MissionError("profile", "reversals are closer than the sampling allows")
    return Phases(bounds=bounds, signs=np.array(signs))


def make_plant(mission: Mission) -> Plant:
    """The mission's plant: the DC motor with the effects of its parameter file (a calibrated plant
    from ``thrustshape fit``), or the normalised torque channel (which takes no effects)."""
    if mission.plant == "dc-motor":
        return mission.dc_plant()
    if isinstance(mission.params, dict) and mission.params.get("effects"):
        raise MissionError("params.effects", "effects act on the dc-motor plant, not on the torque channel")
    return TorquePlant.from_params(mission.motor())


def chain_order(mission: Mission) -> int:
    """Input-chain length: 0 piecewise-constant command, 1 continuous, 2 C^1 (see ocp.optimize.collocation)."""
    base = {ReversalRegularity.BOUNDED: 0, ReversalRegularity.CONTINUOUS_CURRENT: 0,
            ReversalRegularity.CONTINUOUS_VOLTAGE: 1, ReversalRegularity.C1_VOLTAGE: 2}[mission.regularity]
    if mission.limits.voltage_rate is not None:
        base = max(base, 1)  # a slew limit makes the command a state
    return base


def crossing_order(mission: Mission) -> int:
    """Thrust exponent g imposed at reversals: the mission's, else 6 when the voltage must be continuous
    (current and voltage both vanish at the reversal, as for sin^5), else 2."""
    if mission.min_crossing_order is not None:
        return mission.min_crossing_order
    smooth_v = mission.regularity in (ReversalRegularity.CONTINUOUS_VOLTAGE, ReversalRegularity.C1_VOLTAGE)
    return 6 if smooth_v and mission.plant == "dc-motor" else 2


@dataclass
class Problem:
    """Everything one solve needs, derived from a mission (arrays documented in ocp.optimize.collocation)."""

    mission: Mission
    plant: Plant
    structure: col.Structure
    t_desired: np.ndarray
    f_desired: np.ndarray
    phases: Phases


def _plant_key(plant: Plant) -> str:
    return repr(plant)  # frozen dataclasses: constants and effects with their values


def problem_for(mission: Mission) -> Problem:
    """Phases, plant and structure of a mission (no solve)."""
    t, f = mission.desired()
    phases = split_phases(t, f)
    n_phases = phases.signs.size
    total = mission.collocation.intervals
    chain = chain_order(mission)
    # a flat reversal (chain >= 1, omega ~ s^3) needs room on both sides of each boundary
    per_phase = max(MIN_INTERVALS_PER_PHASE[min(chain, 1)], total // n_phases)
    if per_phase * n_phases > 2 * MAX_INTERVALS:
        raise MissionError("collocation.intervals", f"{n_phases} phases need more than {2 * MAX_INTERVALS} intervals")
    plant = make_plant(mission)
    st = col.Structure(plant_key=_plant_key(plant), n_phases=n_phases, intervals=per_phase, chain=chain)
    return Problem(mission=mission, plant=plant, structure=st, t_desired=t, f_desired=f, phases=phases)


#: IPOPT's own wall-time cap [s]: a backstop equal to the largest ``time_limit_s``; a mission's own limit is
#: enforced per call by :class:`_Deadline`, so one built solver serves every time limit
MAX_WALL_TIME_S = 600.0


def ipopt_options(time_limit: float | None = None) -> dict[str, object]:
    """IPOPT options; ``time_limit`` [s] sets ``max_wall_time`` (fixed when the solver is built, so the cached
    solvers leave it at :data:`MAX_WALL_TIME_S` and stop at the mission's limit through :class:`_Deadline`)."""
    return {
        "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
        "ipopt.tol": 1e-7, "ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_iter": 5,
        "ipopt.max_iter": 1000, "ipopt.max_wall_time": float(time_limit or MAX_WALL_TIME_S),
        "ipopt.mu_strategy": "adaptive", "ipopt.linear_solver": "mumps",
    }


class _Deadline(ca.Callback):
    """IPOPT iteration callback that asks IPOPT to stop (``User_Requested_Stop``) once ``perf_counter()``
    passes ``until`` [s]. Its inputs are empty (0x0): no iterate is copied, and one instance serves every
    problem size, so the solver cache is not keyed by the time limit."""

    def __init__(self) -> None:
        ca.Callback.__init__(self)
        self.until = math.inf
        self.construct("deadline", {})

    def get_n_in(self) -> int:
        return int(ca.nlpsol_n_out())

    def get_n_out(self) -> int:
        return 1

    def get_name_in(self, i: int) -> str:
        return str(ca.nlpsol_out(i))

    def get_name_out(self, i: int) -> str:
        return "stop"

    def get_sparsity_in(self, i: int) -> ca.Sparsity:
        return ca.Sparsity(0, 0)

    def eval(self, arg: Any) -> list[float]:
        return [1.0 if time.perf_counter() > self.until else 0.0]


#: ``perf_counter()`` time past which IPOPT stops whatever the mission's time limit (a service worker sets it
#: before its process would be killed, so a build plus a solve never costs the process); inf: none
SOLVE_DEADLINE = [math.inf]
_DEADLINE: list[_Deadline] = []  # one per process, built on the first solve (nothing is built at import)


def _deadline() -> _Deadline:
    if not _DEADLINE:
        _DEADLINE.append(_Deadline())
    return _DEADLINE[0]


def solver_options() -> dict[str, object]:
    """Options of the cached collocation solvers: :func:`ipopt_options` and the deadline callback."""
    return {**ipopt_options(), "iteration_callback": _deadline()}


def optimize(mission: Mission, warm: bool = False) -> OptimizeResult:
    """Optimised reference for ``mission`` (or the analytic fallback with the reason).

    A min-time mission is solved on successively doubled meshes until its duration converges
    (:func:`ocp.optimize.min_time.refine`); any other mission on its own mesh (:func:`optimize_mesh`).
    """
    # --- min-time mesh refinement (issue 15) ---
    if mission.objective == "min-time":
        fastest = fastest_analytic(mission)
        return min_time.refine(mission, lambda m, previous: optimize_mesh(m, warm, previous),
                               None if fastest is None else 0.5 * fastest.period, _mesh_size)
    return optimize_mesh(mission, warm)


def _mesh_size(mission: Mission) -> int:
    """Collocation intervals a solve of ``mission`` uses over all its phases."""
    st = problem_for(mission).structure
    return st.intervals * st.n_phases


def optimize_mesh(mission: Mission, warm: bool = False, previous: OptimizeResult | None = None) -> OptimizeResult:
    """Optimised reference for ``mission`` on its own mesh (or the analytic fallback with the reason);
    ``previous``: a coarser answer of the same mission to start from (min-time refinement).

    When the simulated response exceeds a limit between collocation nodes, the current and voltage
    bounds of the intervals where it does (and of their neighbours) are backed off by the excess (plus
    20 %) and the same cached program is solved again, warm-started (min-time: from the analytic guess).
    """
    started = time.perf_counter()
    problem = problem_for(mission)
    try:
        data = problem_data(problem)
    except MissionError as exc:
        if not exc.field.startswith("limits"):
            raise
        return analytic_fallback(mission, f"limits cannot be met: {exc}")
    if previous is not None:  # min-time refinement: start from the coarser mesh's answer
        data["x0"] = min_time.mesh_guess(problem, data, previous)
    setup = time.perf_counter() - started
    result = solve_problem(problem, data, warm and previous is None)
    build = result.solver.get("build_time_s", 0)
    totals = {k: result.solver.get(k, 0) for k in ("solve_time_s", "verify_time_s", "iterations")}
    backoff, rounds = np.ones((problem.structure.n_phases, problem.structure.intervals)), 0
    for _ in range(MAX_REFINEMENTS):
        if result.source != "optimized" or result.path_ok:
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
        left = max(mission.time_limit_s - totals["solve_time_s"], 1e-3)
        result = solve_problem(problem, data, warm=mission.objective != "min-time", time_limit=left)
        rounds += 1
        for k in totals:
            totals[k] += result.solver.get(k, 0)
    # the report covers every round: times and iterations add up, the build happened in the first
    result.solver.update(totals, build_time_s=build, setup_time_s=setup, backoff_rounds=rounds,
                         limit_backoff=float(np.min(backoff)), backoff_intervals=int(np.sum(backoff < 1.0)))
    if result.source == "optimized" and not result.path_ok:
        diverged = not math.isfinite(result.verification["max_abs_current"] + result.verification["max_abs_voltage"])
        reason = ("the simulated response to the optimised command is not finite" if diverged else
                  f"the optimised response exceeds a limit between nodes after {rounds} back-off rounds")
        result = analytic_fallback(mission, reason, result.solver)
    result.total_time_s = time.perf_counter() - started
    return result


def _interval_excess(problem: Problem, result: OptimizeResult) -> np.ndarray:
    """Largest of |current|/limit and |voltage|/limit (for the torque channel |torque|/limit) of the
    simulated response (on its integration grid) on each collocation interval and its two neighbours (a
    node bounds the polynomials on both sides), shape (P, N)."""
    P, N = problem.structure.n_phases, problem.structure.intervals
    lim, arr = problem.mission.limits, result.fine
    phase_edges = np.concatenate([[0.0], np.cumsum(np.asarray(result.stretch) * problem.phases.durations)])
    t = arr["t"]
    j = np.clip(np.searchsorted(phase_edges, t, side="right") - 1, 0, P - 1)
    k = np.clip(((t - phase_edges[j]) / np.diff(phase_edges)[j] * N).astype(int), 0, N - 1)
    if "torque" in arr:  # the torque channel: its bound is the only one the program keeps
        ratio = np.abs(arr["torque"]) * problem.mission.motor().J / problem.mission.torque_limit()
    else:
        ratio = np.maximum(np.abs(arr["current"]) / lim.current, np.abs(arr["voltage"]) / lim.voltage)
    per = np.zeros(P * N)
    np.maximum.at(per, j * N + k, ratio)
    padded = np.concatenate([[0.0], per, [0.0]])
    return np.maximum(np.maximum(padded[:-2], padded[1:-1]), padded[2:]).reshape(P, N)


def _torque_channel_limit(mission: Mission) -> float | None:
    """The torque bound [N m] of a torque-plant mission, None for the DC motor (its limits are i and V)."""
    return None if mission.plant == "dc-motor" else mission.torque_limit()


def fastest_analytic(mission: Mission) -> SinProfile | None:
    """The fastest ``A sin^(2q+1)`` within the mission's limits and regularity
    (:func:`ocp.reference.fallback.design_sin`) at the larger of the first and last thrust levels, phase 0; half
    its period is the analytic reversal time. None when no period meets the limits."""
    _, f = mission.desired()
    amp = max(abs(float(f[0])), abs(float(f[-1])))
    try:
        return design_sin(mission.motor(), mission.limits.current, mission.limits.voltage, mission.regularity,
                          amplitude=amp, torque_limit=_torque_channel_limit(mission)).profile
    except MissionError:
        return None


# ---------------------------------------------------------------------------------------------
# data: parameters, bounds, initial guess


@dataclass(frozen=True)
class Scales:
    """Per-call scaling: every decision variable is ``value / scale`` (O(1)); SI scales.

    Attributes:
        x: per state (nx,): speed [rad/s], current [A], effect states, input chain [V, V/s, ...]
        u: control scale (input, its slew or its second derivative)
        u_lim: input limit [V] (or normalised torque [rad/s^2])
        f: thrust [N]
    """

    x: np.ndarray
    u: float
    u_lim: float
    f: float


def _scales(problem: Problem, x_full_speed: np.ndarray) -> Scales:
    m, plant, st = problem.mission, problem.plant, problem.structure
    params, lim, dur = m.motor(), m.limits, problem.phases.durations
    f_scale = max(float(np.max(np.abs(problem.f_desired))), 1e-6)
    w_scale = math.sqrt(f_scale / params.c_f)
    if lim.speed is not None and lim.speed < w_scale * math.sqrt(0.999):
        raise MissionError("limits.speed", f"{lim.speed} rad/s cannot produce the desired peak thrust "
                                           f"{f_scale:.4g} N (needs {w_scale:.4g} rad/s)")
    dc = isinstance(plant, DCMotorPlant)
    if dc:
        u_lim = lim.voltage
    else:
        u_lim = m.torque_limit() / params.J
    t_int = float(np.sum(dur)) / (st.n_phases * st.intervals)
    rate = lim.voltage_rate if lim.voltage_rate is not None else u_lim / t_int
    # effect states: their size at full speed; an angle grows with time, scaled by the angle travelled
    angle = max(1.0, w_scale * float(np.sum(dur)))
    effects = [angle if name.endswith(".theta") else max(abs(float(z)), 1e-3)
               for name, z in zip(plant.state_names[2:], x_full_speed[2:], strict=True)] if dc else []
    x = np.array([w_scale] + ([lim.current] if dc else []) + effects + [u_lim, rate][: st.chain])
    return Scales(x=x, u=[u_lim, rate, rate / t_int][st.chain], u_lim=u_lim, f=f_scale)


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
    for j, sign in enumerate(problem.phases.signs):
        w = lay.xc[j, :, :, 0]
        lbx[w], ubx[w] = (0.0, w_max) if sign > 0 else (-w_max, 0.0)
        b = backoff[j][:, None]  # (N, 1) over the interval's points
        if isinstance(problem.plant, DCMotorPlant):
            lbx[lay.xc[j, :, :, 1]], ubx[lay.xc[j, :, :, 1]] = -b, b
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
                 analytic_start: bool = True) -> dict[str, np.ndarray]:
    """Parameter vector, bounds and initial guess for the cached program of ``problem``.

    ``backoff`` (<= 1; a number or one per interval, (P, N)) shrinks the current and voltage bounds relative
    to the limits. The initial guess is the static inverse of the desired thrust at stretch 1, except for a
    min-time mission with reversals and ``analytic_start``: then it is the fastest analytic reversal
    (:func:`_analytic_guess`).
    """
    m, st, plant = problem.mission, problem.structure, problem.plant
    params, lim, dur = m.motor(), m.limits, problem.phases.durations
    P, N, chain = st.n_phases, st.intervals, st.chain
    npx = len(plant.state_names)
    x_start, u0 = equilibrium(plant, speed_for_thrust(plant, float(problem.f_desired[0]), params.c_f))
    w_full = math.sqrt(max(float(np.max(np.abs(problem.f_desired))), 1e-6) / params.c_f)
    sc = _scales(problem, equilibrium(plant, w_full)[0])
    if abs(u0) > sc.u_lim or (isinstance(plant, DCMotorPlant) and abs(x_start[1]) > lim.current):
        raise MissionError("limits", f"the initial thrust {problem.f_desired[0]:.4g} N needs more than the limits")
    rho = _residual_scaling(plant, sc.x, sc.u_lim, N, float(np.mean(dur)), npx, chain)
    # desired thrust at the collocation points, at the same normalised time of each desired phase
    taus = ((np.arange(N)[:, None] + col.TAU[None, 1:]) / N).ravel()  # (N*DEGREE,)
    fd = np.array([np.interp(problem.phases.bounds[j] + taus * dur[j], problem.t_desired, problem.f_desired)
                   for j in range(P)]) / sc.f  # (P, N*DEGREE)
    p = np.concatenate([fd.ravel(), problem.phases.signs, dur, sc.x, [sc.u], rho, [sc.f], WEIGHTS[m.objective]])

    lay = col.layout(P, N, npx + chain)
    lbx, ubx = np.full(lay.n, -np.inf), np.full(lay.n, np.inf)
    _path_bounds(problem, lay, sc, np.broadcast_to(np.asarray(backoff, float), (P, N)), lbx, ubx)
    start = np.array([*x_start, u0, 0.0][: npx + chain])
    _boundary_conditions(problem, lay, sc, start, lbx, ubx)
    x0 = np.zeros(lay.n)
    x0[lay.stretch] = 1.0
    x0[lay.x0] = start / sc.x
    x0 = _initial_guess(problem, lay, x0, fd * sc.f, sc.x, sc.u, chain, lbx, ubx)
    if analytic_start and m.objective == "min-time" and P > 1:
        x0 = _analytic_guess(problem, lay, x0, sc, lbx, ubx)
    return {"p": p, "lbx": lbx, "ubx": ubx, "x0": x0, "xscale": sc.x, "uscale": np.array([sc.u]),
            "f_scale": np.array([sc.f])}


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


def _initial_guess(problem: Problem, lay: col.Layout, x0: np.ndarray, fd: np.ndarray, xscale: np.ndarray,
                   uscale: float, chain: int, lbx: np.ndarray, ubx: np.ndarray) -> np.ndarray:
    """Static inverse of the desired thrust at the collocation points (nominal steady current and
    input), effect states held at their initial values; clipped into the bounds."""
    params = problem.mission.motor()
    P, N = problem.structure.n_phases, problem.structure.intervals
    npx = len(problem.plant.state_names)
    guess = x0.copy()
    start = x0[lay.x0]
    for j in range(P):
        w = problem.phases.signs[j] * np.abs(speed_from_thrust(fd[j], params.c_f).reshape(N, col.DEGREE))
        if isinstance(problem.plant, TorquePlant):
            i, u = np.zeros_like(w), problem.plant.k * w * np.abs(w)
        else:
            i = (params.B * w + params.c_tau * w * np.abs(w)) / params.k_t
            u = params.R * i + params.k_e * w
        for k in range(2, npx):
            guess[lay.xc[j, :, :, k]] = start[k]
        guess[lay.xc[j, :, :, 0]] = w / xscale[0]
        if npx > 1:
            guess[lay.xc[j, :, :, 1]] = i / xscale[1]
        if chain >= 1:
            guess[lay.xc[j, :, :, npx]] = u / xscale[npx]
        if chain == 0:
            guess[lay.u[j, :, 0]] = u[:, -1] / uscale
    return np.clip(guess, lbx, ubx)


def _analytic_guess(problem: Problem, lay: col.Layout, guess: np.ndarray, sc: Scales, lbx: np.ndarray,
                    ubx: np.ndarray) -> np.ndarray:
    """Min-time initial guess from the analytic fallback: the fastest ``A sin^(2q+1)`` within the limits
    (:func:`fastest_analytic`), started at its peak of the first phase's sign, so phase j lasts a quarter
    period at either end and half a period in between; states and input are its exact feedforward
    (nominal plant) at the retimed collocation points. Unchanged when no sine meets the limits."""
    m, st = problem.mission, problem.structure
    fastest = fastest_analytic(m)
    if fastest is None:
        return guess
    P, N, chain = st.n_phases, st.intervals, st.chain
    npx = len(problem.plant.state_names)
    quarter = 0.25 * fastest.period
    h = np.full(P, 2.0 * quarter)
    h[0] = h[-1] = quarter
    edges = np.concatenate([[0.0], np.cumsum(h)])
    taus = ((np.arange(N)[:, None] + col.TAU[None, 1:]) / N).ravel()  # (N*DEGREE,)
    t = (edges[:-1, None] + taus[None, :] * h[:, None]).ravel()  # (P*N*DEGREE,) strictly increasing
    prof = SinProfile(fastest.amplitude, fastest.period, fastest.q, phase=0.5 * math.pi * problem.phases.signs[0])
    ref = reference(prof, m.motor(), t)
    if isinstance(problem.plant, TorquePlant):
        # eq:omega_dyn  u = w' + k w|w|
        chain_0, current = ref.omega_dot + problem.plant.k * ref.omega * np.abs(ref.omega), None
    else:
        chain_0, current = ref.voltage, ref.current
    inputs = [chain_0]  # input, its slew, its second derivative at the points
    for _ in range(chain):
        inputs.append(np.gradient(inputs[-1], t))
    out = guess.copy()
    out[lay.stretch] = h / problem.phases.durations
    shape = (P, N, col.DEGREE)
    out[lay.xc[:, :, :, 0]] = ref.omega.reshape(shape) / sc.x[0]
    if current is not None:
        out[lay.xc[:, :, :, 1]] = current.reshape(shape) / sc.x[1]
    for c in range(chain):
        out[lay.xc[:, :, :, npx + c]] = inputs[c].reshape(shape) / sc.x[npx + c]
    out[lay.u[:, :, 0]] = inputs[chain].reshape(shape)[:, :, -1] / sc.u
    return np.clip(out, lbx, ubx)


def solve_problem(problem: Problem, data: dict[str, np.ndarray], warm: bool,
                  time_limit: float | None = None) -> OptimizeResult:
    """Solve the cached program; IPOPT stops after ``time_limit`` [s] of solving (default the mission's
    ``time_limit_s``; building the program is not counted, as with IPOPT's own ``max_wall_time``)."""
    m = problem.mission
    build_start = time.perf_counter()
    prog = col.solver_for(problem.plant, problem.structure, solver_options())
    build_time = time.perf_counter() - build_start
    budget = m.time_limit_s if time_limit is None else time_limit
    args: dict[str, Any] = {"x0": data["x0"], "p": data["p"], "lbx": data["lbx"], "ubx": data["ubx"],
                            "lbg": 0.0, "ubg": 0.0}
    with prog.lock:
        if warm and "x" in prog.last and prog.last["x"].size == data["x0"].size:
            args["x0"] = np.clip(prog.last["x"], data["lbx"], data["ubx"])
            args["lam_x0"], args["lam_g0"] = prog.last["lam_x"], prog.last["lam_g"]
        t0 = time.perf_counter()
        _deadline().until = min(t0 + budget, SOLVE_DEADLINE[0])
        try:
            sol = prog.solver(**args)
        finally:
            _deadline().until = math.inf
        solve_time = time.perf_counter() - t0
        stats = prog.solver.stats()
        x = np.asarray(sol["x"]).ravel()
        prog.last = {"x": x, "lam_x": np.asarray(sol["lam_x"]).ravel(), "lam_g": np.asarray(sol["lam_g"]).ravel()}
    status = str(stats.get("return_status", "unknown"))
    ok = bool(stats.get("success", False)) or status == "Solved_To_Acceptable_Level"
    g_viol = float(np.max(np.abs(np.asarray(sol["g"])))) if prog.n_g else 0.0
    solver_info = {"status": status, "iterations": int(stats.get("iter_count", -1)), "solve_time_s": solve_time,
                   "build_time_s": build_time, "objective": float(sol["f"]), "constraint_violation": g_viol}
    if not ok:
        reason = ("solver time limit reached" if "Wall" in status or "CPU" in status or status == "User_Requested_Stop"
                  else f"IPOPT: {status}")
        return analytic_fallback(m, reason, solver_info)
    t0 = time.perf_counter()
    result = finish_result(problem, prog, x, data, solver_info)
    result.solver["verify_time_s"] = time.perf_counter() - t0
    return result
