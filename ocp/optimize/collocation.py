"""Direct collocation program for thrust references, built once per structure and solved many times.

The horizon is split into phases at the reversals of the desired thrust. In phase ``j`` the sign
``sigma_j`` of the speed is fixed, so ``w|w| = sigma_j w^2`` is smooth (a parameter, not structure),
and the phase lasts ``h_j = stretch_j * d_j`` (retiming; ``d_j`` is the desired duration). Each phase
has ``N`` Radau IIA intervals of degree 3 in the normalised time ``tau in [0, 1]``; the tracking target
at a collocation point is the desired thrust at the same normalised time of the desired phase, so
retiming never changes the data, only ``h_j``.

State ``x = (plant states, input chain)``: the plant input (voltage or torque) is the control itself
(``chain = 0``, piecewise constant: bounded command), or a state driven by its slew (``chain = 1``,
continuous command), or by its second derivative (``chain = 2``, C^1 command).

Everything that changes between calls is data: parameters (desired thrust, signs, durations, scales,
weights) and variable bounds (limits, sign constraints, boundary and crossing conditions). The NLP
depends only on :class:`Structure`, and one solver per structure is cached (:func:`solver_for`).
All decision variables are scaled to O(1) by per-call scale parameters.

The :class:`Program` owns its parameter layout (:meth:`Program.pack` checks named parts against the
builder's slices), its lock, its warm-start memory and its wall-time stop (:meth:`Program.solve`); a
caller's limits of one call (deadline, build observer) come in a :class:`SolveContext`.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from typing import Any

import casadi as ca
import numpy as np

from ocp.model.plant import CASADI, Plant
from ocp.optimize import path_limits
from ocp.optimize import warm as warm_
from ocp.optimize.nlp_call import call
from ocp.optimize.program_cache import ProgramCache

DEGREE = 3
TAU = np.append(0.0, ca.collocation_points(DEGREE, "radau"))  # (DEGREE+1,) interval-local nodes


def _lagrange_tables(tau: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Derivative matrix C[j, r] = l_j'(tau_r) and quadrature weights B[j] = int_0^1 l_j."""
    n = tau.size
    C = np.zeros((n, n))
    B = np.zeros(n)
    for j in range(n):
        poly = np.poly1d([1.0])
        for r in range(n):
            if r != j:
                poly *= np.poly1d([1.0, -tau[r]]) / (tau[j] - tau[r])
        der = np.polyder(poly)
        C[j] = [der(tr) for tr in tau]
        B[j] = np.polyint(poly)(1.0)
    return C, B


C_MAT, B_QUAD = _lagrange_tables(TAU)


def lagrange_basis(s: np.ndarray) -> np.ndarray:
    """Values of the DEGREE+1 Lagrange polynomials on ``TAU`` at points ``s`` (M,): shape (M, DEGREE+1)."""
    s = np.asarray(s, float)
    out = np.ones((s.size, TAU.size))
    for j in range(TAU.size):
        for r in range(TAU.size):
            if r != j:
                out[:, j] *= (s - TAU[r]) / (TAU[j] - TAU[r])
    return out


@dataclass(frozen=True)
class Structure:
    """What the NLP's shape depends on (the cache key, with the plant's identity).

    Attributes:
        plant_key: hashable identity of the plant constants and effects
        n_phases: number of phases (reversals + 1)
        intervals: collocation intervals per phase
        chain: 0 piecewise-constant input, 1 continuous input (slew control), 2 C^1 input
    """

    plant_key: str
    n_phases: int
    intervals: int
    chain: int


@dataclass
class Layout:
    """Index maps of the decision vector; arrays of indices into ``x``.

    Shapes: ``stretch`` (P,), ``x0`` (nx,), ``xc`` (P, N, DEGREE, nx), ``u`` (P, N, nu=1).
    """

    stretch: np.ndarray
    x0: np.ndarray
    xc: np.ndarray
    u: np.ndarray
    n: int


#: IPOPT's own wall-time cap [s]: a backstop equal to the largest ``time_limit_s``; a call's own limit is
#: enforced by the program's :class:`_Deadline`, so one built solver serves every time limit
MAX_WALL_TIME_S = 600.0


def ipopt_options(time_limit: float | None = None) -> dict[str, object]:
    """IPOPT options; ``time_limit`` [s] sets ``max_wall_time`` (fixed when the solver is built, so the cached
    solvers leave it at :data:`MAX_WALL_TIME_S` and stop at the call's limit through :class:`_Deadline`)."""
    return {
        "ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes",
        "ipopt.tol": 1e-7, "ipopt.acceptable_tol": 1e-4, "ipopt.acceptable_iter": 5,
        "ipopt.max_iter": 1000, "ipopt.max_wall_time": float(time_limit or MAX_WALL_TIME_S),
        "ipopt.mu_strategy": "adaptive", "ipopt.linear_solver": "mumps",
    }


def solver_options() -> dict[str, object]:
    """Options of the cached collocation solvers (the cache key :func:`ocp.optimize.solve.optimize` uses): the
    wall-time limit is not among them (see :class:`_Deadline`)."""
    return ipopt_options()


@dataclass(frozen=True)
class SolveContext:
    """What a caller imposes on one call beyond the mission (a service worker's, say).

    Attributes:
        deadline: ``time.perf_counter()`` time [s] past which IPOPT stops whatever the mission's time limit (a
            worker sets it before its process would be killed); inf: none
        on_build: called with ``"build"`` before a program is built and ``"built"`` once it is cached (a worker
            tells its parent, which then keeps a build that outlives a request's deadline)
    """

    deadline: float = math.inf
    on_build: Callable[[str], None] | None = None


class _Deadline(ca.Callback):
    """IPOPT iteration callback that asks IPOPT to stop (``User_Requested_Stop``) once ``perf_counter()``
    passes ``until`` [s]. Its inputs are empty (0x0): no iterate is copied. One per program, set under its lock,
    so the solver cache is not keyed by the time limit."""

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


@dataclass(frozen=True)
class Solved:
    """One IPOPT run of a program.

    Attributes:
        x: decision vector (scaled), shape (layout.n,)
        status: IPOPT return status
        success: IPOPT succeeded or stopped at its acceptable level
        iterations: IPOPT iterations
        objective: objective value [1]
        constraint_violation: largest |g| of the (scaled) collocation residuals
        solve_time_s: wall time of the run [s]
        warm, warm_build_s: started from the program's last solution; time [s] spent building the warm solver
        method: the NLP solver of the answer: ``ipopt``, or ``sqp`` (the flat program's, :mod:`ocp.optimize.sqp`)
        compiled: the SQP evaluated its functions compiled to C (:mod:`ocp.optimize.native_nlp`)
    """

    x: np.ndarray
    status: str
    success: bool
    iterations: int
    objective: float
    constraint_violation: float
    solve_time_s: float
    warm: bool = False
    warm_build_s: float = 0.0
    method: str = "ipopt"
    compiled: bool = False



@dataclass
class Program:
    """A built NLP with its solvers (cold; warm, built on a warm start: :mod:`ocp.optimize.warm`), layout, a
    warm-start memory, a lock and a wall-time stop. Constraints: the collocation residuals (``n_g``, equalities),
    then the current inside each interval (``n_path``, :func:`ocp.optimize.path_limits.path_bounds`)."""

    structure: Structure
    nx: int
    n_plant_states: int
    solver: ca.Function
    layout: Layout
    n_params: int
    n_g: int
    deadline: _Deadline = field(repr=False)
    n_path: int = 0
    nlp: dict[str, ca.SX] = field(default_factory=dict, repr=False)  # for the warm solver's build
    ipopt_options: dict[str, object] = field(default_factory=dict, repr=False)
    build_s: float = 0.0  # time the cold solver took to build [s]
    warm_solver: ca.Function | None = field(default=None, repr=False)
    _last: warm_.Memory | None = field(default=None, repr=False)
    _lock: threading.Lock = field(default_factory=threading.Lock, repr=False)

    @cached_property
    def param_slices(self) -> dict[str, slice]:
        return _param_slices(self.structure, self.nx)

    def pack(self, **named: np.ndarray | float | tuple[float, ...]) -> np.ndarray:
        """The parameter vector from its named parts (the keys of :attr:`param_slices`: fd, sigma, dur, xscale,
        uscale, rho, fscale, weights), each checked against the builder's slice; shape (n_params,)."""
        slices = self.param_slices
        if set(named) != set(slices):
            raise ValueError(f"pack needs exactly {sorted(slices)}; got {sorted(named)}")
        p = np.empty(self.n_params)
        for name, sl in slices.items():
            part = np.ravel(np.asarray(named[name], float))
            if part.size != sl.stop - sl.start:
                raise ValueError(f"parameter {name!r} has {part.size} values; the program takes {sl.stop - sl.start}")
            p[sl] = part
        return p

    @property
    def last_solution(self) -> np.ndarray | None:
        """A copy of the decision vector of the last solve (scaled), None before the first (benchmarks)."""
        with self._lock:
            return None if self._last is None else self._last.x.copy()

    def unpack(self, p: np.ndarray) -> dict[str, np.ndarray]:
        """The named parts of a parameter vector (views), the inverse of :meth:`pack`."""
        return {name: p[sl] for name, sl in self.param_slices.items()}

    def _warm_solver(self, until: float) -> ca.Function:
        """The warm solver, built on first use (under the lock) if the call's stop ``until`` leaves room for three
        cold builds (``build_s``); else, until a roomier call builds it, the cold solver."""
        if self.warm_solver is None and until - time.perf_counter() < 3.0 * self.build_s:
            return self.solver
        if self.warm_solver is None:
            self.warm_solver = ca.nlpsol("collocation_warm", "ipopt", self.nlp,
                                         {**self.ipopt_options, **warm_.WARM_OPTIONS,  # type: ignore[dict-item]
                                          "iteration_callback": self.deadline})
        return self.warm_solver

    def solve(self, p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, x0: np.ndarray, warm: bool | None = False,
              until: float = math.inf, path_bound: np.ndarray | None = None) -> Solved:
        """One IPOPT run from ``x0``, or from this program's last solution and multipliers (clipped into the
        bounds; the warm solver) when ``warm`` is True or, ``None``, when the last solve is plausibly close;
        stopped once ``perf_counter()`` passes ``until`` [s]. ``path_bound``: bounds of the in-interval current
        (|i| / limit, shape (n_path,); default 1). Thread-safe."""
        bound = np.ones(self.n_path) if path_bound is None or not self.n_path else path_bound
        lbg, ubg = np.concatenate([np.zeros(self.n_g), -bound]), np.concatenate([np.zeros(self.n_g), bound])
        args: dict[str, Any] = {"x0": x0, "p": p, "lbx": lbx, "ubx": ubx, "lbg": lbg, "ubg": ubg}
        with self._lock:
            solver, t_lock = self.solver, time.perf_counter()
            started_warm = warm_.start_from(self._last, warm, p, lbx, ubx, self.param_slices)
            if started_warm and self._last is not None:
                args["x0"] = np.clip(self._last.x, lbx, ubx)
                args["lam_x0"], args["lam_g0"] = self._last.lam_x, self._last.lam_g
                solver = self._warm_solver(until)  # built on first use: its time is reported apart
            t0 = time.perf_counter()
            self.deadline.until = until
            try:
                run = call(solver, args)
            finally:
                self.deadline.until = math.inf
            sol = run.sol
            x = np.asarray(sol["x"]).ravel()
            self._last = warm_.Memory(x=x, lam_x=np.asarray(sol["lam_x"]).ravel(),
                                      lam_g=np.asarray(sol["lam_g"]).ravel(), p=p.copy(), lbx=lbx.copy(),
                                      ubx=ubx.copy())
        g = np.asarray(sol["g"]).ravel()[:self.n_g]
        return Solved(x=x, status=run.status, success=run.success, iterations=run.iterations, objective=float(sol["f"]),
                      constraint_violation=float(np.max(np.abs(g))) if self.n_g else 0.0,
                      solve_time_s=run.seconds, warm=started_warm, warm_build_s=t0 - t_lock)


def _param_slices(st: Structure, nx: int) -> dict[str, slice]:
    """Layout of the parameter vector."""
    sizes = {
        "fd": st.n_phases * st.intervals * DEGREE,  # desired thrust at collocation points / f_scale
        "sigma": st.n_phases,  # speed sign per phase
        "dur": st.n_phases,  # desired phase durations d_j [s]
        "xscale": nx,  # state scales
        "uscale": 1,  # control scale
        "rho": nx,  # residual scaling per state
        "fscale": 1,  # thrust scale [N]
        "weights": 5,  # track, time, stretch, smooth, effort
    }
    out, k = {}, 0
    for name, size in sizes.items():
        out[name] = slice(k, k + size)
        k += size
    return out


def build(plant: Plant, st: Structure, ipopt_options: dict[str, object]) -> Program:
    """Build the NLP for ``plant`` with structure ``st`` (seconds at most; then cached)."""
    started = time.perf_counter()
    npx = len(plant.state_names)
    nx = npx + st.chain
    P, N = st.n_phases, st.intervals
    ps = _param_slices(st, nx)
    n_par = max(s.stop for s in ps.values())
    par = ca.SX.sym("p", n_par)
    fd = ca.reshape(par[ps["fd"]], DEGREE * N, P)
    sigma, dur = par[ps["sigma"]], par[ps["dur"]]
    xs, us, rho = par[ps["xscale"]], par[ps["uscale"]], par[ps["rho"]]
    fscale = par[ps["fscale"]]
    w_track, w_time, w_stretch, w_smooth, w_effort = (par[ps["weights"]][i] for i in range(5))

    stretch = ca.SX.sym("stretch", P)
    x0 = ca.SX.sym("x0", nx)
    xc = [[ca.SX.sym(f"xc_{j}_{k}", nx, DEGREE) for k in range(N)] for j in range(P)]
    u = [[ca.SX.sym(f"u_{j}_{k}", 1) for k in range(N)] for j in range(P)]

    g: list[ca.SX] = []
    g_path: list[ca.SX] = []
    path = path_limits.applies(plant, st.chain)
    u_all: list[ca.SX] = []
    f_track = ca.SX(0.0)
    total = ca.sum1(dur)
    x_start = x0
    interval = _interval_function(plant, st, nx, npx)  # one interval's equations, inlined below (fast build)
    for j in range(P):
        h = stretch[j] * dur[j]
        for k in range(N):
            pts = ca.horzcat(x_start, xc[j][k])  # (nx, DEGREE+1) scaled
            uk = u[j][k]
            u_all.append(uk)
            res, err2 = interval(pts, uk, sigma[j], xs, us, rho, h / N, fscale, fd[k * DEGREE:(k + 1) * DEGREE, j])
            g += ca.vertsplit(res, nx)
            if path:  # the current between the nodes (issue 14 item 1)
                g_path.append(path_limits.current_terms(plant, TAU, st.chain, npx, pts, uk, xs, us, h / N))
            f_track += dur[j] / (N * total) * err2
            x_start = xc[j][k][:, DEGREE - 1]
    u_vec = ca.vertcat(*u_all)
    n_u = P * N
    f_time = ca.dot(stretch, dur) / total
    f_stretch = ca.dot(stretch - 1, dur) / total
    f_smooth = ca.sumsqr(u_vec[1:] - u_vec[:-1]) / n_u
    f_effort = ca.sumsqr(u_vec) / n_u
    obj = w_track * f_track + w_time * f_time + w_stretch * f_stretch + w_smooth * f_smooth + w_effort * f_effort

    xs_list = [stretch, x0]
    for j in range(P):
        for k in range(N):
            xs_list += [ca.vec(xc[j][k]), u[j][k]]
    xvec = ca.vertcat(*xs_list)
    deadline = _Deadline()
    nlp = {"x": xvec, "f": obj, "g": ca.vertcat(*g, *g_path), "p": par}
    solver = ca.nlpsol("collocation", "ipopt", nlp,
                       {**ipopt_options, "iteration_callback": deadline})  # type: ignore[dict-item]
    return Program(structure=st, nx=nx, n_plant_states=npx, solver=solver, layout=layout(P, N, nx),
                   n_params=n_par, n_g=int(ca.vertcat(*g).numel()), deadline=deadline,
                   n_path=int(ca.vertcat(*g_path).numel()) if g_path else 0, nlp=nlp,
                   ipopt_options=dict(ipopt_options), build_s=time.perf_counter() - started)


def _interval_function(plant: Plant, st: Structure, nx: int, npx: int) -> ca.Function:
    """One interval's collocation residuals and quadrature-weighted squared tracking error, as an SX function
    ``(pts (nx, DEGREE+1), u, sigma, xscale (nx,), uscale, rho (nx,), h/N [s], fscale [N], fd (DEGREE,))
    -> (residuals (nx*DEGREE,), sum_r B_r err_r^2)``; calling it on SX arguments inlines it."""
    pts, uk, sig = ca.SX.sym("pts", nx, DEGREE + 1), ca.SX.sym("u"), ca.SX.sym("sigma")
    xs, us, rho, hn = ca.SX.sym("xs", nx), ca.SX.sym("us"), ca.SX.sym("rho", nx), ca.SX.sym("hn")
    fscale, fd = ca.SX.sym("fscale"), ca.SX.sym("fd", DEGREE)
    res: list[ca.SX] = []
    err2 = ca.SX(0.0)
    for r in range(1, DEGREE + 1):
        xr = pts[:, r] * xs
        plant_u = xr[npx] if st.chain else uk * us
        dx = plant.rhs([xr[m] for m in range(npx)], plant_u, CASADI, sig)
        chain_dx = [xr[npx + c + 1] for c in range(st.chain - 1)] + ([uk * us] if st.chain else [])
        fx = ca.vertcat(*dx, *chain_dx)
        slope = ca.mtimes(pts, C_MAT[:, r])
        res.append(rho * (slope - hn * fx / xs))
        thrust = plant.thrust([xr[m] for m in range(npx)], CASADI, sig)
        err2 += B_QUAD[r] * (thrust / fscale - fd[r - 1]) ** 2
    return ca.Function("interval", [pts, uk, sig, xs, us, rho, hn, fscale, fd], [ca.vertcat(*res), err2])


@lru_cache(maxsize=64)
def layout(P: int, N: int, nx: int) -> Layout:
    """Index maps of the decision vector for P phases of N intervals and nx states (cached)."""
    stretch = np.arange(P)
    x0 = P + np.arange(nx)
    xc = np.zeros((P, N, DEGREE, nx), dtype=int)
    uu = np.zeros((P, N, 1), dtype=int)
    k = P + nx
    for j in range(P):
        for i in range(N):
            # ca.vec is column-major: element (m, r) of the (nx, DEGREE) block sits at r*nx + m
            for r in range(DEGREE):
                xc[j, i, r, :] = k + r * nx + np.arange(nx)
            k += nx * DEGREE
            uu[j, i, 0] = k
            k += 1
    return Layout(stretch=stretch, x0=x0, xc=xc, u=uu, n=k)


CACHE_SIZE = 8  # built programs kept per process (tens of MB each), least recently used evicted
_CACHE: ProgramCache[Program] = ProgramCache(CACHE_SIZE)


def solver_for(plant: Plant, st: Structure, ipopt_options: dict[str, object],
               on_build: Callable[[str], None] | None = None) -> Program:
    """The cached :class:`Program` for this structure and options (built on first use; LRU of CACHE_SIZE);
    ``on_build`` (:attr:`SolveContext.on_build`) hears of a build."""
    key = (st, tuple(sorted((k, str(v)) for k, v in ipopt_options.items())))
    return _CACHE.get(key, lambda: build(plant, st, ipopt_options), on_build)[0]


def clear_cache() -> None:
    """Forget every built program (used by benchmarks to measure build cost)."""
    _CACHE.clear()
