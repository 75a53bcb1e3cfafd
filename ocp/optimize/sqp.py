"""The flat program's first solver: a line-search SQP whose QPs are dense and convex, solved by DAQP hot-started.

The flat NLP (:mod:`ocp.optimize.flat`) has tens of variables and hundreds of limit rows of which few are active.
CasADi's ``sqpmethod`` with the sparse qpOASES took 3 to 6 iterations where IPOPT takes 6 to 27, but 85-90 % of
its time was qpOASES solving each QP from scratch (36 of 40 ms on ``user-sine-0.5hz-b``). This loop keeps its
iterations and makes each QP cheap:

* the QP's variables are the free ones (coefficients fixed by equal bounds are left out);
* its Hessian is the exact Hessian of the Lagrangian (``H``, indefinite: a tracking residual that the limits keep
  from zero curves the objective down), plus ``rho`` times the normalised rows of the previous QP's working set
  ``R'R``: on the null space of those rows ``H`` is unchanged, so where the working set is the optimum's the step
  is the exact Newton step (with eigenvalues reflected instead, ``|w|``, the 0.5 Hz bounded sine converged
  linearly, 17 iterations); curvature still negative on that null space is shifted off by the smallest multiple
  of the identity that makes the QP strictly convex, as DAQP needs (:func:`convexified`);
* each QP starts from the previous one's working set (:mod:`ocp.optimize.daqp`; the first from a warm start's
  multipliers, or empty), over the rows near their bounds only (:func:`screened`; the others checked after);
* a step is accepted on the l1 merit function ``f + nu * violation`` (backtracking, ``nu`` above the largest
  row multiplier).

It stops when the largest row violation and the gradient of the Lagrangian (over the largest multiplier, as
IPOPT's scaled dual error) are both below :data:`TOL` (the objective is scaled to 1 at the start,
:func:`ocp.optimize.flat.objective_scaled`: IPOPT's ``tol`` is 1e-7 too) or a feasible point's QP step is below
:data:`MIN_MOVE`; it fails after :data:`MAX_ITER` iterations, on a QP DAQP cannot solve or a step the merit function
rejects, and stops between iterations once the program's deadline passes (``callback.until``,
:class:`collocation._Deadline`); IPOPT then solves the same NLP (:func:`ocp.optimize.flat.solve`). The solver is
called like a CasADi NLP solver (keyword arguments ``x0, p, lbx, ubx, lbg, ubg, lam_x0, lam_g0``; ``stats()``
with ``success``, ``iter_count``, ``return_status`` in IPOPT's words).
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import casadi as ca
import numpy as np

from ocp.optimize import daqp, native_nlp

MAX_ITER = 50  # SQP iterations before IPOPT takes over (the bench missions need 2 to 6)
#: largest row violation, and largest entry of the Lagrangian's gradient over max(1, largest multiplier), at a
#: solution (scaled objective)
TOL = 1e-7
FLOOR = 1e-5  # smallest Cholesky pivot of a QP's Hessian, relative to its largest entry
SHIFTS = 20  # multiples of the identity tried (FLOOR times the scale, then 4x each)
#: weights of the working set's rows tried, times the scale: over 10 flat missions (6 user, 4 classic) 48-49 SQP
#: iterations in all with a first weight of 0.1-0.3, 51 with 1, 68 with 100 (a wrong working set is then hard
#: to leave) and 119 with 0.03 (too weak: the identity shifts take over)
RHO = (0.3, 3.0, 30.0)
ROUND_OFF = 1e-15  # relative change of the merit function the line search takes for no change
ARMIJO = 1e-8  # sufficient decrease of the merit function, times the step and its directional derivative
MIN_STEP = 1e-8  # a backtracking line search that needs a shorter step fails
#: a QP step this small (the variables are O(1): stretches and scaled coefficients) from a feasible point ends the
#: solve (IPOPT and this loop then agree to 1e-7 relative in the objective)
MIN_MOVE = 1e-8
#: the multipliers of a warm start that count as active (relative to the largest): IPOPT's are never exactly 0
ACTIVE_REL = 1e-6
#: rows farther than this from their bounds (scaled: the limits are 1) are left out of a QP and checked after it
SCREEN = 0.1


class _Buffered:
    """A CasADi function evaluated into preallocated numpy arrays (``Function.buffer``: no conversion per call)."""

    def __init__(self, fn: ca.Function) -> None:
        self.fn = fn
        self.args = [np.zeros(fn.nnz_in(i)) for i in range(fn.n_in())]
        self.res = [np.zeros(fn.nnz_out(i)) for i in range(fn.n_out())]
        self._buf, self._trigger = fn.buffer()
        for i, a in enumerate(self.args):
            self._buf.set_arg(i, a.data)  # type: ignore[call-arg]  # the stub's size is not taken
        for i, r in enumerate(self.res):
            self._buf.set_res(i, r.data)  # type: ignore[call-arg]

    def __call__(self, *args: np.ndarray | float) -> list[np.ndarray]:
        for dst, src in zip(self.args, args, strict=True):
            dst[:] = src
        self._trigger()
        return self.res


def _dense_index(sp: ca.Sparsity) -> np.ndarray:
    """Flat (row-major) indices into the dense matrix of the nonzeros of ``sp``, shape (nnz,)."""
    rows, cols = sp.get_triplet()
    return np.asarray(rows, int) * sp.size2() + np.asarray(cols, int)


@dataclass
class _Functions:
    """The NLP's functions: objective and rows at a trial point, gradient and Jacobian, Hessian of the Lagrangian
    (upper triangle), with the dense positions of their nonzeros."""

    f: _Buffered
    g: _Buffered
    grad: _Buffered
    jac: _Buffered
    hess: _Buffered
    jac_index: np.ndarray
    hess_index: np.ndarray
    hess_index_t: np.ndarray
    n_x: int
    n_g: int


_NAMES = {"f": "nlp_f", "g": "nlp_g", "grad": "nlp_grad_f", "jac": "nlp_jac_g", "hess": "nlp_hess_l"}


def _vm_functions(nlp: Mapping[str, ca.SX], cold: ca.Function | None) -> dict[str, ca.Function]:
    """The functions of ``nlp`` (keys of :data:`_NAMES`), taken from the IPOPT solver ``cold`` built from it (no
    second symbolic Hessian, most of the program's build) or derived here."""
    if cold is not None:
        return {k: cold.get_function(name) for k, name in _NAMES.items()}
    x, p, f, g = nlp["x"], nlp["p"], nlp["f"], nlp["g"]
    lam_f, lam_g = ca.SX.sym("lam_f"), ca.SX.sym("lam_g", g.shape[0])
    hess = ca.triu(ca.hessian(lam_f * f + ca.dot(lam_g, g), x)[0])
    return {"f": ca.Function("nlp_f", [x, p], [f]), "g": ca.Function("nlp_g", [x, p], [g]),
            "grad": ca.Function("nlp_grad_f", [x, p], [f, ca.gradient(f, x)]),
            "jac": ca.Function("nlp_jac_g", [x, p], [g, ca.jacobian(g, x)]),
            "hess": ca.Function("nlp_hess_l", [x, p, lam_f, lam_g], [hess])}


def _functions(fns: Mapping[str, ca.Function]) -> _Functions:
    """The functions ``fns`` (keys of :data:`_NAMES`) buffered, with the dense positions of their nonzeros."""
    sp_j, sp_h = fns["jac"].sparsity_out(1), fns["hess"].sparsity_out(0)
    rows, cols = sp_h.get_triplet()
    n = sp_h.size1()
    return _Functions(f=_Buffered(fns["f"]), g=_Buffered(fns["g"]), grad=_Buffered(fns["grad"]),
                      jac=_Buffered(fns["jac"]), hess=_Buffered(fns["hess"]), jac_index=_dense_index(sp_j),
                      hess_index=_dense_index(sp_h), hess_index_t=np.asarray(cols, int) * n + np.asarray(rows, int),
                      n_x=n, n_g=sp_j.size1())


def convexified(H: np.ndarray, rows: np.ndarray) -> np.ndarray:
    """A positive definite QP Hessian from the Lagrangian's ``H`` (n, n): plus ``rho R'R`` for the working set's
    rows ``R`` (k, n) (normalised here; ``rho`` :data:`RHO` times the largest entry of ``H``), which leaves ``H``
    on their null space, the first ``rho`` whose sum is positive definite (Cholesky pivots above :data:`FLOOR` of
    that entry); failing that (negative curvature on the null space), the first ``rho`` plus the smallest multiple
    of the identity (:data:`SHIFTS`) that makes it so. No
    eigendecomposition: numpy's threaded LAPACK took 2.4-38 ms for one 60 x 60 ``eigh`` on this shared 2-core
    machine, a Cholesky factor 0.06 ms."""
    scale = max(float(np.max(np.abs(H), initial=0.0)), 1e-12)
    eye = np.eye(H.shape[0])
    gram = eye * 0.0
    if rows.size:
        unit = rows / np.maximum(np.sqrt(np.einsum("ij,ij->i", rows, rows)), 1e-300)[:, None]
        gram = unit.T @ unit
    # first the rows' weight grows (H unchanged on their null space), then a multiple of the identity is added
    tries = [(rho * scale, 0.0) for rho in (RHO if rows.size else (0.0,))]
    tries += [(tries[0][0], FLOOR * scale * 4.0**k) for k in range(SHIFTS)]
    for rho, shift in tries:
        B = H + rho * gram + shift * eye
        try:
            pivots = np.diag(np.linalg.cholesky(B)) ** 2
        except np.linalg.LinAlgError:
            continue
        if np.min(pivots, initial=math.inf) >= FLOOR * scale:
            return B
    raise np.linalg.LinAlgError("no positive definite shift of the QP's Hessian")


def screened(solve: Callable[..., daqp.QPResult | None], B: np.ndarray, grad: np.ndarray, A: np.ndarray,
             lower: np.ndarray, upper: np.ndarray, ws: np.ndarray, base: np.ndarray) -> daqp.QPResult | None:
    """The QP ``min 0.5 d'Bd + grad'd``, ``lower <= (d; A d) <= upper`` (bounds (n + m,)) by ``solve`` (the
    arguments of :func:`ocp.optimize.daqp.solve`) over the rows within :data:`SCREEN` of a bound or in the working
    set ``ws`` ((n + m,) flags; ``base`` the equality rows'); rows left out that the answer breaks are added (with
    those it brings within SCREEN) and the QP solved again from its working set, until none is broken: the answer
    is the full QP's (a row that does not bind does not move its optimum). Multipliers (n + m,), 0 off the rows
    solved with."""
    nf = grad.size
    slack = np.minimum(upper[nf:], -lower[nf:])
    keep = (slack <= SCREEN) | (ws[nf:] & daqp.ACTIVE != 0)
    start = ws
    for _ in range(len(slack) + 1):
        sel = np.concatenate([np.arange(nf), nf + np.flatnonzero(keep)])
        res = solve(B, grad, A[keep], lower[sel], upper[sel], start[sel])
        if res is None:
            return None
        lam = np.zeros(lower.size)
        lam[sel] = res.lam
        lin = A @ res.x
        out = ~keep & ((lin > upper[nf:] + daqp.PRIMAL_TOL) | (lin < lower[nf:] - daqp.PRIMAL_TOL))
        if not np.any(out):
            return daqp.QPResult(x=res.x, lam=lam, exitflag=res.exitflag, iterations=res.iterations)
        keep |= out | (np.minimum(upper[nf:] - lin, lin - lower[nf:]) <= SCREEN)
        start = daqp.working_set(lam, base)
    return None


@dataclass
class _State:
    """The SQP's iterate: x (n_x,), objective f, gradient (n_x,), rows g (n_g,), Jacobian (n_g, n_x)."""

    x: np.ndarray
    f: float
    grad: np.ndarray
    g: np.ndarray
    jac: np.ndarray


class Solver:
    """The flat NLP's SQP solver (see the module's docstring), called like a CasADi NLP solver."""

    def __init__(self, name: str, nlp: Mapping[str, ca.SX], callback: Any, cold: ca.Function | None = None,
                 max_iter: int = MAX_ITER) -> None:
        self.name, self.max_iter = name, max_iter
        self.callback = callback
        vm = _vm_functions(nlp, cold)
        self.vm_fns = self.fns = _functions(vm)
        #: the same functions compiled to C once the program is hot (:mod:`ocp.optimize.native_nlp`)
        self.native = native_nlp.NativeNLP(vm)
        self._native_fns: _Functions | None = None
        self.allow_native = True  # False: the virtual machine only (benchmarks compare both)
        self._jac = np.zeros((self.fns.n_g, self.fns.n_x))
        self._stats: dict[str, Any] = {}

    def use_native(self, wait: bool = False) -> bool:
        """Switch to the compiled functions if their library is ready (``wait``: build it now); whether they are
        in use."""
        if self._native_fns is None:
            fns = self.native.get(wait=True) if wait else self.native.poll()
            if fns is not None:
                self._native_fns = _functions(fns)
        self.fns = self._native_fns or self.vm_fns
        return self._native_fns is not None

    @property
    def compiled(self) -> bool:
        """Whether the last call evaluated the compiled functions."""
        return self.fns is not self.vm_fns

    def stats(self) -> dict[str, Any]:
        """The last call's ``success``, ``iter_count``, ``return_status`` and the QP solver's share
        (``qp_iterations``, ``t_wall_qp`` [s])."""
        return dict(self._stats)

    def _state(self, x: np.ndarray, p: np.ndarray) -> _State:
        f, grad = self.fns.grad(x, p)
        g, nz = self.fns.jac(x, p)
        self._jac.flat[self.fns.jac_index] = nz
        return _State(x=x.copy(), f=float(f[0]), grad=grad.copy(), g=g.copy(), jac=self._jac.copy())

    def _hessian(self, x: np.ndarray, p: np.ndarray, lam_g: np.ndarray) -> np.ndarray:
        (nz,) = self.fns.hess(x, p, 1.0, lam_g)
        H = np.zeros((self.fns.n_x, self.fns.n_x))
        H.flat[self.fns.hess_index] = nz
        H.flat[self.fns.hess_index_t] = nz
        return H

    def __call__(self, **args: Any) -> dict[str, Any]:
        if self.allow_native:
            self.use_native()
        else:
            self.fns = self.vm_fns
        lbx, ubx = (np.asarray(args[k], float).ravel() for k in ("lbx", "ubx"))
        lbg, ubg = (np.asarray(args[k], float).ravel() for k in ("lbg", "ubg"))
        p = np.asarray(args["p"], float).ravel()
        x0 = np.clip(np.asarray(args["x0"], float).ravel(), lbx, ubx)
        lam_g = np.asarray(args.get("lam_g0", np.zeros(lbg.size)), float).ravel().copy()
        lam_x = np.asarray(args.get("lam_x0", np.zeros(x0.size)), float).ravel()
        free = np.flatnonzero(lbx < ubx)
        base = np.zeros(free.size + lbg.size, np.int32)
        base[free.size:][lbg == ubg] = daqp.EQUALITY
        start = np.concatenate([lam_x[free], lam_g])
        big = float(np.max(np.abs(start), initial=0.0))
        ws = daqp.working_set(np.where(np.abs(start) > ACTIVE_REL * big, start, 0.0), base)
        out = _Loop(self, p, lbx, ubx, lbg, ubg, free, base).run(self._state(x0, p), lam_g, ws)
        self._stats = out.stats
        return out.sol


@dataclass
class _Result:
    sol: dict[str, Any]
    stats: dict[str, Any]


class _Loop:
    """One call's iterations (data fixed, iterate moving)."""

    def __init__(self, solver: Solver, p: np.ndarray, lbx: np.ndarray, ubx: np.ndarray, lbg: np.ndarray,
                 ubg: np.ndarray, free: np.ndarray, base: np.ndarray) -> None:
        self.s, self.p, self.lbx, self.ubx, self.lbg, self.ubg = solver, p, lbx, ubx, lbg, ubg
        self.free, self.base = free, base
        self.eye = np.eye(free.size)
        self.qp_iterations, self.qp_seconds = 0, 0.0

    def violation(self, g: np.ndarray) -> float:
        """The l1 norm of the rows' violation of their bounds."""
        return float(np.maximum(g - self.ubg, 0.0).sum() + np.maximum(self.lbg - g, 0.0).sum())

    def run(self, st: _State, lam_g: np.ndarray, ws: np.ndarray) -> _Result:
        nf, free = self.free.size, self.free
        lam_x = np.zeros(st.x.size)
        nu, status = 0.0, "Maximum_Iterations_Exceeded"
        fixed = np.setdiff1d(np.arange(st.x.size), free)
        for it in range(self.s.max_iter + 1):
            # the fixed variables' multipliers close the gradient of the Lagrangian; the free ones' are the QP's
            gradient = st.grad + st.jac.T @ lam_g
            lam_x[fixed] = -gradient[fixed]
            primal = float(np.max(np.maximum(st.g - self.ubg, self.lbg - st.g), initial=0.0))
            dual = float(np.max(np.abs(gradient + lam_x), initial=0.0))
            # the dual error relative to the multipliers (IPOPT's s_d: a stretch at its bound carries a multiplier
            # of ~4e3 on the 2 s reversal, and the gradient is then exact only to ~1e-5)
            if primal <= TOL and dual <= TOL * max(1.0, float(np.max(np.abs(lam_g), initial=0.0)),
                                                   float(np.max(np.abs(lam_x), initial=0.0))):
                status = "Solve_Succeeded"
                break
            if it == self.s.max_iter:
                break
            if time.perf_counter() > self.s.callback.until:
                status = "User_Requested_Stop"
                break
            qp = self.qp(st, lam_g, ws)
            if qp is None:
                status = "Error_In_Step_Computation"
                break
            d = np.zeros(st.x.size)
            d[free] = qp.x
            if primal <= TOL and float(np.max(np.abs(qp.x), initial=0.0)) <= MIN_MOVE:
                status = "Solve_Succeeded"  # a KKT point to round-off: the scaled gradient may still be ~1e-6
                break
            ws = daqp.working_set(qp.lam, self.base)
            lam_rows = qp.lam[nf:]
            nu = max(nu, 1.1 * float(np.max(np.abs(lam_rows), initial=0.0)))
            step = self.line_search(st, d, nu)
            if step is None:
                status = "Search_Direction_Becomes_Too_Small"
                break
            alpha, st = step
            lam_g = lam_g + alpha * (lam_rows - lam_g)
            lam_x[free] = lam_x[free] + alpha * (qp.lam[:nf] - lam_x[free])
        success = status == "Solve_Succeeded"
        sol = {"x": st.x, "f": st.f, "g": st.g, "lam_g": lam_g, "lam_x": lam_x}
        return _Result(sol, {"success": success, "iter_count": it, "return_status": status,
                             "qp_iterations": self.qp_iterations, "t_wall_qp": self.qp_seconds})

    def qp(self, st: _State, lam_g: np.ndarray, ws: np.ndarray) -> daqp.QPResult | None:
        """The step's QP over the free variables, from the working set ``ws`` (and cold if that fails)."""
        free = self.free
        H = self.s._hessian(st.x, self.p, lam_g)[np.ix_(free, free)]
        A = st.jac[:, free]
        active = ws & daqp.ACTIVE != 0
        rows = np.concatenate([self.eye[active[: free.size]], A[active[free.size:]]])
        try:
            B = convexified(H, rows)
        except np.linalg.LinAlgError:  # not a finite Hessian
            return None
        lower = np.concatenate([self.lbx[free] - st.x[free], self.lbg - st.g])
        upper = np.concatenate([self.ubx[free] - st.x[free], self.ubg - st.g])
        return screened(self.solve, B, st.grad[free], A, lower, upper, ws, self.base)

    def solve(self, B: np.ndarray, grad: np.ndarray, A: np.ndarray, lower: np.ndarray, upper: np.ndarray,
              start: np.ndarray) -> daqp.QPResult | None:
        """One DAQP solve from the working set ``start``, and from none if that fails."""
        for flags in (start, np.where(start & daqp.IMMUTABLE, start, 0).astype(np.int32)):
            t0 = time.perf_counter()
            res = daqp.solve(B, grad, A, lower, upper, flags)
            self.qp_seconds += time.perf_counter() - t0
            self.qp_iterations += res.iterations
            if res.success:
                return res
        return None

    def line_search(self, st: _State, d: np.ndarray, nu: float) -> tuple[float, _State] | None:
        """Backtracking on the l1 merit function from ``st`` along ``d``: (step, new iterate), or ``None``."""
        v0 = self.violation(st.g)
        merit0 = st.f + nu * v0
        slope = float(st.grad @ d) - nu * v0
        alpha = 1.0
        while alpha >= MIN_STEP:
            trial = self.s._state(np.clip(st.x + alpha * d, self.lbx, self.ubx), self.p)
            if trial.f + nu * self.violation(trial.g) <= merit0 + ARMIJO * alpha * slope + ROUND_OFF * abs(merit0):
                return alpha, trial
            alpha *= 0.5
        return None


def build(name: str, nlp: Mapping[str, ca.SX], callback: Any, cold: ca.Function | None = None,
          max_iter: int = MAX_ITER) -> Solver:
    """The SQP solver of ``nlp`` with the program's deadline ``callback`` (its ``until`` [s] of
    ``perf_counter``); ``cold``: the IPOPT solver of the same ``nlp``, whose derivative functions it shares."""
    return Solver(name, nlp, callback, cold, max_iter)
