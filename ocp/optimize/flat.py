"""The flat program: the speed per phase as a B-spline, current and voltage from it (issue 14 item 3).

The voltage-driven DC motor with its propeller is differentially flat in the speed ``omega``: along any
smooth ``omega(t)`` the current and the voltage that produce it follow in closed form,

    i = (J w' + B w + c_tau w|w|) / k_t            (eq. dc_mechanical)
    V = R i + L i' + k_e w                          (eq. dc_electrical)
    F = c_f w|w|                                     (eq. thrust_model)

so the program needs no states and no collocation residuals. In phase ``j`` (speed sign ``sigma_j``, desired
duration ``d_j``, retimed length ``h_j = stretch_j d_j``) ``omega`` is a clamped B-spline of degree
:data:`DEGREE` on :attr:`FlatStructure.spans` uniform spans of the normalised time ``tau in [0, 1]``, with
coefficients ``c_j`` (scaled by the speed scale). Decision variables: the stretches and the coefficients, a
few tens per phase against ~1,200 of the Radau program.

Everything the Radau program imposes is kept, as bounds where the B-spline's properties allow it:

* speed sign and speed limit: ``0 <= sigma_j c_j <= w_max`` (a B-spline lies in the hull of its coefficients);
* start at the mission's equilibrium: ``omega(0) = w_0`` and ``omega'(0) = 0`` (the current is the equilibrium
  one), and ``omega''(0) = 0`` when the voltage is continuous (chain >= 1), ``omega'''(0) = 0`` for a C^1
  voltage: the first coefficients equal (a clamped spline's r-th derivative at 0 uses ``c_0..c_r`` only);
* reversal: ``omega = 0`` at each phase boundary (last and first coefficient zero); crossing order 6
  (``omega ~ s^3``) also ``omega' = omega'' = 0`` on both sides (three coefficients zero), so current and voltage
  vanish there; order 2 keeps the current continuous (``omega'`` continuous in physical time), a continuous
  voltage also ``omega''``, a C^1 voltage ``omega'''`` (equalities across the two phases' lengths);
* ``|i| <= I (1 - MARGIN)`` and ``|V| <= V (1 - MARGIN)`` at :data:`CHECKS` points per span (:data:`END_CHECKS`
  in the spans nearest the phase ends); the verified answer (the command simulated on the integration grid)
  decides, with back-off rounds (:mod:`ocp.optimize.flat_solve`) and then the Radau program (:mod:`ocp.optimize.solve`).

The objective is the Radau program's (``ocp.optimize.data.WEIGHTS``): tracking at the same normalised time of the
desired phase (Gauss quadrature per span), stretch, and the smoothness and effort of the Radau program's control
(input, its slew or its second derivative by the chain) sampled at the middle of each span and scaled to the Radau
program's sums over its intervals. :mod:`ocp.optimize.evaluate` scores either program's answer alike.
Plant constants, scales and limits are parameters: one solver per :class:`FlatStructure` is built and cached.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import lru_cache
from typing import Any

import casadi as ca
import numpy as np
from scipy.interpolate import BSpline

from ocp.optimize import collocation as col
from ocp.optimize import daqp, sqp
from ocp.optimize import warm as warm_
from ocp.optimize.nlp_call import Call, call
from ocp.optimize.program_cache import ProgramCache

DEGREE = 5  # omega: C^4 inside a phase, so the voltage is C^2 and its slew C^1
CHECKS = 3  # limit check points per span (equally spaced)
#: ... in the first and last spans of a phase (outermost first), where a reversal's held voltage may jump and the
#: current turns fastest. Every check is two limit rows, and a solver's time per iteration grows with the rows: 3
#: a span and (12, 8, 8) at the ends (98 rows a phase at 20 spans) took 30-40 % less IPOPT time per iteration than
#: 4 and 12 in 3 end spans (128 rows); with 8 in the 3 end spans the step reversal needed a back-off round
#: (overshoot in the last span)
END_CHECKS = (12, 8, 8)
GAUSS = 4  # Gauss-Legendre points per span for the tracking integral
#: knots graded towards the phase ends: a reversal with omega ~ s^3 needs fine spans there (the continuous-voltage
#: reversal's tracking objective fell by 8x from uniform spans to GRADE 0.8 at 20 spans; 0.5 keeps the middle of
#: a phase resolved for a ramp's corners)
GRADE = 0.5
#: IPOPT options of the flat program over the Radau program's: a monotone barrier (the adaptive one's mu oracle
#: cost more than it saved on these small programs: 46 vs 79 ms on the 2 s reversal, 75 vs 124 ms on user-ramp-cv),
#: started at mu 1e-3 (the guess is inside the current limit, :func:`ocp.optimize.flat_solve._guess`) and left as
#: soon as its subproblem is solved to 100 mu (not 10): 6 to 23 iterations on the user missions instead of 10 to
#: 28, the same optimum (relative 1e-3)
IPOPT_OPTIONS = {"ipopt.mu_strategy": "monotone", "ipopt.mu_init": 1e-3, "ipopt.barrier_tol_factor": 100.0}
MARGIN = 5e-3  # the current and voltage bounds at the check points are the limits times (1 - MARGIN)
CACHE_SIZE = 16


@dataclass(frozen=True)
class FlatStructure:
    """What the flat NLP's shape depends on (its cache key; plant constants are parameters).

    The Radau program's intervals per phase (the smoothness and effort terms' normalisation) are a parameter
    (``intervals``, :func:`param_slices`), not part of the key: missions of 40 and 60 intervals whose phases get
    the same spans share one program (on ``bench/batch.py``'s mix 5 flat structures instead of 6).

    Attributes:
        n_phases: phases (reversals + 1); spans: B-spline spans per phase
        chain: the Radau program's input chain (0 held, 1 continuous, 2 C^1 voltage)
        order6: crossing order 6 (omega ~ s^3) instead of 2
    """

    n_phases: int
    spans: int
    chain: int
    order6: bool

    @property
    def n_coef(self) -> int:
        return self.spans + DEGREE


@lru_cache(maxsize=32)
def knots(spans: int) -> np.ndarray:
    """Clamped knot vector on [0, 1], graded towards both ends (``u - GRADE sin(2 pi u) / (2 pi)`` of uniform
    ``u``: the end spans are ``1 - GRADE`` of the uniform width, the middle ones ``1 + GRADE``), shape
    (spans + 2 DEGREE + 1,)."""
    u = np.linspace(0.0, 1.0, spans + 1)
    return np.concatenate([np.zeros(DEGREE), u - GRADE * np.sin(2 * np.pi * u) / (2 * np.pi), np.ones(DEGREE)])


def basis(spans: int, tau: np.ndarray, order: int) -> np.ndarray:
    """``order``-th tau-derivative of every basis function at ``tau`` (M,): shape (M, spans + DEGREE). One spline
    with the identity as its coefficients (column k: basis function k; the same arithmetic per column as one
    spline per function, 25x faster)."""
    t, n = knots(spans), spans + DEGREE
    spline = BSpline(t, np.eye(n), DEGREE, extrapolate=True)
    return np.asarray((spline.derivative(order) if order else spline)(np.asarray(tau, float)))


@lru_cache(maxsize=32)
def quad_basis(spans: int) -> np.ndarray:
    """The basis at the Gauss points of :func:`points` (the initial guess's least squares), (spans GAUSS, n_coef)."""
    return basis(spans, points(spans)["quad"], 0)


@lru_cache(maxsize=32)
def points(spans: int) -> dict[str, np.ndarray]:
    """Normalised times of one phase: limit checks ``check`` (CHECKS per span, END_CHECKS in the first and last
    spans, outermost first; the phase's end included),
    Gauss points ``quad`` (spans GAUSS,) with weights ``weight`` (sum 1), and ``mid`` (spans,) the spans'
    midpoints, where the smoothness and effort terms sample the control."""
    g, wg = np.polynomial.legendre.leggauss(GAUSS)
    edges = knots(spans)[DEGREE:-DEGREE]
    width = np.diff(edges)
    quad = (edges[:-1, None] + 0.5 * (g[None, :] + 1.0) * width[:, None]).ravel()
    per = np.full(spans, CHECKS)
    ends = np.array(END_CHECKS[: spans // 2])
    per[: ends.size], per[spans - ends.size:] = ends, ends[::-1]
    check = np.append(np.concatenate([a + np.arange(n) / n * w for a, n, w in zip(edges[:-1], per, width,
                                                                                  strict=True)]), 1.0)
    return {"check": check, "quad": quad, "weight": (0.5 * wg[None, :] * width[:, None]).ravel(),
            "mid": 0.5 * (edges[:-1] + edges[1:])}


def drive(w: list[Any], k: dict[str, Any], sigma: Any, upto: int) -> list[Any]:
    """(current [A], voltage [V], voltage slew [V/s], ...) from the speed and its time derivatives ``w`` =
    (w, w', w'', ...) [rad/s, rad/s^2, ...]; ``upto`` the highest voltage derivative wanted (0..2). ``k``: the
    plant constants (J, B, c_tau, k_t, k_e, R, L). Symbolic (CasADi) or numeric (numpy arrays (M,))."""
    # eq:dc_mechanical  k_t i = J w' + B w + c_tau sigma w^2, and its time derivatives
    sq = [w[0] ** 2, 2 * w[0] * w[1], 2 * (w[1] ** 2 + w[0] * w[2]), 2 * (3 * w[1] * w[2] + w[0] * w[3])]
    cur = [(k["J"] * w[r + 1] + k["B"] * w[r] + k["c_tau"] * sigma * sq[r]) / k["k_t"] for r in range(upto + 2)]
    # eq:dc_electrical  V = R i + L i' + k_e w, and its time derivatives
    volts = [k["R"] * cur[r] + k["L"] * cur[r + 1] + k["k_e"] * w[r] for r in range(upto + 1)]
    return [cur[0], *volts]


CONSTANTS = ("J", "B", "c_tau", "k_t", "k_e", "R", "L", "c_f")
SCALES = ("w", "f", "i", "v", "u")  # speed [rad/s], thrust [N], current [A], voltage [V], control


@lru_cache(maxsize=64)
def param_slices(st: FlatStructure) -> dict[str, slice]:
    """Layout of the parameter vector (cached per structure: every solve asks; read it, never change it)."""
    nq = st.spans * GAUSS
    sizes = {"constants": len(CONSTANTS), "scales": len(SCALES), "sigma": st.n_phases, "dur": st.n_phases,
             "fd": st.n_phases * nq, "weights": 5, "intervals": 1, "obj_scale": 1}
    out, k = {}, 0
    for name, size in sizes.items():
        out[name] = slice(k, k + size)
        k += size
    return out


@dataclass
class FlatProgram:
    """A built flat NLP: ``x = (stretch (P,), c (P * n_coef,))``; ``g = (current, voltage at the check points,
    each (P * n_check,), scaled by the limits; continuity equalities)``. With its SQP solver (tried first,
    :mod:`ocp.optimize.sqp`), its cold and warm IPOPT solvers (:mod:`ocp.optimize.warm`) and the memory of its last
    few successful solves (oldest first)."""

    structure: FlatStructure
    solver: ca.Function
    n_params: int
    n_check: int
    n_cont: int
    deadline: col._Deadline
    build_s: float
    lock: threading.Lock
    objective: ca.Function  # f(x, p), the cold solver's own (:func:`objective_scaled`)
    nlp: dict[str, ca.SX] = field(default_factory=dict, repr=False)  # for the warm solver's build
    options: dict[str, object] = field(default_factory=dict, repr=False)  # the cold solver's options
    warm_solver: ca.Function | None = field(default=None, repr=False)  # built by program_for
    sqp_solver: sqp.Solver | None = field(default=None, repr=False)  # built by program_for (:mod:`ocp.optimize.sqp`)
    memory: deque[warm_.Memory] = field(default_factory=lambda: deque(maxlen=warm_.MEMORIES), repr=False)

    @property
    def n_x(self) -> int:
        return self.structure.n_phases * (1 + self.structure.n_coef)

    def pack(self, **named: np.ndarray | float | tuple[float, ...]) -> np.ndarray:
        """The parameter vector from its named parts (:func:`param_slices`), each checked for its size."""
        p = np.empty(self.n_params)
        for name, sl in param_slices(self.structure).items():
            part = np.ravel(np.asarray(named[name], float))
            if part.size != sl.stop - sl.start:
                raise ValueError(f"parameter {name!r} has {part.size} values; the program takes {sl.stop - sl.start}")
            p[sl] = part
        return p

    def g_bounds(self, current: float, voltage: float) -> tuple[np.ndarray, np.ndarray]:
        """Bounds of ``g``: |i| / scale <= ``current``, |V| / scale <= ``voltage`` (scaled), continuity = 0."""
        P = self.structure.n_phases
        ub = np.concatenate([np.full(P * self.n_check, current), np.full(P * self.n_check, voltage),
                             np.zeros(self.n_cont)])
        lb = -ub
        return lb, ub


def _phase_terms(st: FlatStructure, c: ca.SX, h: ca.SX, sigma: ca.SX, k: dict[str, ca.SX], ws: ca.SX,
                 tables: dict[str, list[np.ndarray]]) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
    """(current (n_check,), voltage (n_check,), speed at the Gauss points (nq,), control at the midpoints
    (spans,)) of one phase, SI; ``c`` its scaled coefficients, ``h`` its length [s]."""
    def derivs(name: str, upto: int) -> list[ca.SX]:
        return [ca.mtimes(_sparse(tables[name][r]), c) * ws / h**r for r in range(upto + 1)]

    wc = [*derivs("check", 2), ca.SX(0.0)]
    i_v = drive(wc, k, sigma, 0)
    wm = derivs("mid", st.chain + 2) + [ca.SX(0.0)] * (2 - st.chain)
    u = drive(wm, k, sigma, st.chain)[1 + st.chain]
    wq = ca.mtimes(_sparse(tables["quad"][0]), c) * ws
    return i_v[0], i_v[1], wq, u


def _sparse(table: np.ndarray) -> ca.DM:
    """A basis table as a sparse constant (a B-spline's local support: DEGREE + 1 nonzeros a row)."""
    return ca.sparsify(ca.DM(np.where(np.abs(table) > 1e-14 * np.max(np.abs(table)), table, 0.0)))


def build(st: FlatStructure) -> FlatProgram:
    """Build the flat NLP of structure ``st`` (tens of milliseconds; then cached by :func:`program_for`)."""
    started = time.perf_counter()
    P, nc = st.n_phases, st.n_coef
    pts = points(st.spans)
    tables = {name: [basis(st.spans, pts[name], r) for r in range(5)] for name in ("check", "quad", "mid")}
    ends = {side: [basis(st.spans, np.array([side]), r) for r in range(4)] for side in (0.0, 1.0)}
    ps = param_slices(st)
    n_par = max(s.stop for s in ps.values())
    par = ca.SX.sym("p", n_par)
    k = dict(zip(CONSTANTS, ca.vertsplit(par[ps["constants"]]), strict=True))
    sc = dict(zip(SCALES, ca.vertsplit(par[ps["scales"]]), strict=True))
    sigma, dur = par[ps["sigma"]], par[ps["dur"]]
    fd = ca.reshape(par[ps["fd"]], st.spans * GAUSS, P)
    w_track, _, w_stretch, w_smooth, w_effort = (par[ps["weights"]][r] for r in range(5))
    n_int = par[ps["intervals"]]  # the Radau program's intervals per phase
    stretch = ca.SX.sym("stretch", P)
    coef = [ca.SX.sym(f"c{j}", nc) for j in range(P)]
    total = ca.sum1(dur)
    g_i, g_v, u_all = [], [], []
    f_track = ca.SX(0.0)
    weight = ca.DM(pts["weight"])
    for j in range(P):
        h = stretch[j] * dur[j]
        cur, volts, wq, u = _phase_terms(st, coef[j], h, sigma[j], k, sc["w"], tables)
        g_i.append(cur / sc["i"])
        g_v.append(volts / sc["v"])
        u_all.append(u / sc["u"])
        # eq:thrust_model  F = c_f w|w| = c_f sigma w^2 in phase j
        err = k["c_f"] * sigma[j] * wq**2 / sc["f"] - fd[:, j]
        f_track += dur[j] / total * ca.dot(weight, err**2)
    g_cont = _continuity(st, coef, stretch * dur, ends)
    u_vec = ca.vertcat(*u_all)
    # the Radau program's sum over its P N intervals of (u_{k+1} - u_k)^2 / (P N) and u_k^2 / (P N), from one
    # sample a span: a difference across a span is N / spans of the Radau program's, squared, over spans / N terms
    ratio = st.spans / n_int
    # times obj_scale (1 / the objective at the initial guess, :func:`objective_scaled`): IPOPT's tolerances are
    # absolute, and unscaled objectives of 1e-7 .. 1e-2 stopped a cold solve up to ~1 % above the optimum
    obj = par[ps["obj_scale"]] * (w_track * f_track + w_stretch * ca.dot(stretch - 1, dur) / total
                                  + w_smooth * ratio * ca.sumsqr(u_vec[1:] - u_vec[:-1]) / (P * n_int)
                                  + w_effort * ca.sumsqr(u_vec) / (P * st.spans))
    nlp = {"x": ca.vertcat(stretch, *coef), "f": obj, "g": ca.vertcat(*g_i, *g_v, *g_cont), "p": par}
    deadline = col._Deadline()
    options = {**col.solver_options(), **IPOPT_OPTIONS}
    solver = ca.nlpsol("flat", "ipopt", nlp, {**options, "iteration_callback": deadline})  # type: ignore[dict-item]
    return FlatProgram(structure=st, solver=solver, n_params=n_par, n_check=pts["check"].size,
                       n_cont=len(g_cont), deadline=deadline, build_s=time.perf_counter() - started,
                       lock=threading.Lock(), nlp=nlp, options=options, objective=solver.get_function("nlp_f"))


def continuity_orders(st: FlatStructure) -> list[int]:
    """Derivative orders of omega that must be continuous (physical time) across a reversal: the current
    (omega'), a continuous voltage (omega''), a C^1 voltage (omega'''); the ones order 6 makes zero are bounds."""
    wanted = list(range(1, st.chain + 2))
    return [r for r in wanted if not (st.order6 and r <= 2)]


def _continuity(st: FlatStructure, coef: list[ca.SX], h: ca.SX,
                ends: dict[float, list[np.ndarray]]) -> list[ca.SX]:
    """omega^(r) (left end of phase j) h_{j+1}^r = omega^(r) (right start of phase j+1) h_j^r, per order r."""
    out = []
    for j in range(st.n_phases - 1):
        for r in continuity_orders(st):
            left = ca.mtimes(ca.DM(ends[1.0][r]), coef[j])
            right = ca.mtimes(ca.DM(ends[0.0][r]), coef[j + 1])
            out.append(left * h[j + 1] ** r - right * h[j] ** r)
    return out


_CACHE: ProgramCache[FlatProgram] = ProgramCache(CACHE_SIZE)


def program_for(st: FlatStructure, on_build: Callable[[str], None] | None = None) -> tuple[FlatProgram, float]:
    """The cached flat program of ``st`` (built on first use; least recently used evicted) and the time [s]
    this call spent building it (0 when cached); ``on_build`` hears of a build (:class:`ProgramCache`)."""
    prog, built = _CACHE.get(st, lambda: _with_solvers(build(st)), on_build)
    return prog, prog.build_s if built else 0.0


def clear_cache() -> None:
    """Forget every built flat program (benchmarks)."""
    _CACHE.clear()


#: the flat program's parameter parts that must be equal / within WARM_CLOSE for a start from its memory
WARM_EXACT, WARM_NEAR = ("sigma", "weights"), ("constants", "scales", "dur", "intervals")
#: largest distance (:func:`ocp.optimize.warm.distances`) of a remembered solve the flat program starts from: on
#: the first 150 items of ``bench/batch.py``'s mix (seed 7), IPOPT took 10 -> 2 iterations cold -> warm below
#: 0.05, 13 -> 7.5 at 0.05-0.1, the same at 0.1-0.15 and 10 -> 12.5 at 0.15-0.2 (``warm.CLOSE`` is 0.25)
WARM_CLOSE = 0.1


def objective_scaled(prog: FlatProgram, p: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """``p`` (n_params,) with ``obj_scale`` set to 1 / the objective at the start ``x0`` (n_x,), so that IPOPT's
    absolute tolerances are relative to the mission's own objective (1 where it is not positive and finite)."""
    q, sl = p.copy(), param_slices(prog.structure)["obj_scale"]
    q[sl] = 1.0
    f0 = float(prog.objective(x0, q))
    q[sl] = 1.0 / f0 if math.isfinite(f0) and f0 > 0.0 else 1.0
    return q


def solve(prog: FlatProgram, p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, x0: np.ndarray,
          g_bounds: tuple[np.ndarray, np.ndarray], until: float = math.inf, warm: bool | None = False) -> col.Solved:
    """One solve of the flat program from ``x0`` (n_x,), or from a remembered successful solve (primal and dual):
    the last when ``warm`` is True or, ``None``, the nearest plausibly close one (:func:`ocp.optimize.warm.pick`);
    stopped once ``perf_counter()`` passes ``until`` [s]. The SQP solver (:mod:`ocp.optimize.sqp`) runs first; where
    it fails IPOPT (the warm solver from a remembered solve) runs from the same start, and the times and iterations
    add up. The objective reported is unscaled (``p``'s ``obj_scale`` divided out). Thread-safe."""
    args = {"x0": x0, "p": p, "lbx": lbx, "ubx": ubx, "lbg": g_bounds[0], "ubg": g_bounds[1]}
    scale = param_slices(prog.structure)["obj_scale"]
    with prog.lock:
        ipopt = prog.solver
        start = warm_.pick(prog.memory, warm, p, lbx, ubx, param_slices(prog.structure), WARM_EXACT, WARM_NEAR,
                           WARM_CLOSE)
        if start is not None:
            args.update(warm_.warm_args(start, lbx, ubx))
            # multipliers scale with the objective: from the remembered solve's objective scale to this one's
            ratio = float(p[scale][0] / start.p[scale][0])
            args["lam_x0"], args["lam_g0"] = args["lam_x0"] * ratio, args["lam_g0"] * ratio
            ipopt = prog.warm_solver or ipopt
        prog.deadline.until = until
        try:
            runs: list[Call] = []
            if prog.sqp_solver is not None:
                runs.append(call(prog.sqp_solver, args))
            if not runs or not runs[0].success:
                runs.append(call(ipopt, args))
        finally:
            prog.deadline.until = math.inf
        last = runs[-1]
        if last.success:  # a failed run is no start for the next call
            prog.memory.append(warm_.remember(last.sol, p, lbx, ubx))
    g = np.asarray(last.sol["g"]).ravel()
    viol = float(np.max(np.maximum(g - g_bounds[1], g_bounds[0] - g), initial=0.0))
    return col.Solved(x=np.asarray(last.sol["x"]).ravel(), status=last.status, success=last.success,
                      iterations=sum(r.iterations for r in runs), objective=float(last.sol["f"]) / float(p[scale][0]),
                      constraint_violation=viol, solve_time_s=sum(r.seconds for r in runs), warm=start is not None,
                      method="sqp" if last.solver is prog.sqp_solver else "ipopt",
                      compiled=last.solver is prog.sqp_solver and prog.sqp_solver.compiled)


def _with_solvers(prog: FlatProgram) -> FlatProgram:
    """``prog`` with its warm solver (built from the cold one's derivative functions, ~15 % of the cold build) and
    its SQP solver: they come with the program, so a call's time limit never has to leave room for them."""
    started = time.perf_counter()
    prog.warm_solver = warm_.build_solver("flat_warm", prog.nlp, prog.options, prog.deadline, prog.solver)
    prog.sqp_solver = sqp.build("flat_sqp", prog.nlp, prog.deadline, prog.solver) if daqp.available() else None
    prog.build_s += time.perf_counter() - started
    return prog
