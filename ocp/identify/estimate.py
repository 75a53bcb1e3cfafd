"""Least-squares estimation of candidate parameters (scipy ``least_squares``, trust-region reflective).

* :func:`equation_error_fit` -- minimise the one-step equation residuals (``ocp.identify.predict``),
  each equation scaled by its residual RMS under the starting plant; cheap (vectorised over samples),
  and for amplitude-type parameters (friction, offsets, drops) the problem is linear in them. The torque
  equation is seen as the speed error it causes (:func:`.regression.speed_view` at the starting plant's rotor
  time constant, as :func:`ocp.identify.diagnose` sees it): its residual is ``J`` times the differentiated speed,
  whose noise, taken as signal, biased ``J`` low (a fifth to a half of the rig's on proving-ground logs at
  2-10 kHz) before the refinement repaired it.
* :func:`free_run_fit` -- minimise the free-run errors (speed, current, thrust, each scaled by its
  sensor-noise level); the refinement step, robust to noise in the regressors.

Both return an :class:`Estimate` with Gauss-Newton uncertainties: ``cov = s^2 (J^T J)^-1`` with
``s^2`` the residual variance. Residuals of the free run are correlated in time, so its standard
errors are optimistic; they are reported for comparison, not as confidence intervals.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares, lsq_linear

from ocp.errors import SolverError
from ocp.identify.candidates import Candidate
from ocp.identify.predict import CHANNELS, EQUATIONS, free_run, one_step, run_rows
from ocp.identify.regression import speed_view
from ocp.identify.resolution import rotor_tau
from ocp.logs import Log, LogKind
from ocp.model.plant import DCMotorPlant


@dataclass(frozen=True)
class Estimate:
    """Fitted values of some candidates.

    Attributes:
        plant: the plant with the fitted values in
        names: ``"<candidate>.<key>"`` per fitted parameter, (P,)
        values: (P,) SI
        stderr: standard errors (P,) SI (``inf`` when not identifiable)
        correlation: (P, P)
        cost: final sum of squared scaled residuals / 2
    """

    plant: DCMotorPlant
    names: tuple[str, ...]
    values: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    cost: float


def assemble(base: DCMotorPlant, cands: Sequence[Candidate], theta: np.ndarray) -> DCMotorPlant:
    """``base`` with the candidates' parameters taken from the flat vector ``theta``."""
    plant, k = base, 0
    for c in cands:
        plant = c.apply(plant, [float(v) for v in theta[k:k + len(c.keys)]])
        k += len(c.keys)
    return plant


def peak_torque(base: DCMotorPlant, log: Log) -> float:
    """The motor's torque scale in ``log`` [N m]: the largest of ``k_t`` times the largest logged current [A], the
    largest logged reaction torque, and the plant's drag ``B |w| + c_tau w^2`` at the log's peak speed (a sweep may
    log no current, or the supply's, which understates the armature's at part throttle); absent columns count 0."""
    p, w = base.params, float(np.nanmax(np.abs(log.omega), initial=0.0))
    return max(p.k_t * float(np.nanmax(np.abs(log.current), initial=0.0)),
               float(np.nanmax(np.abs(log.torque), initial=0.0)) if log.torque is not None else 0.0,
               p.B * w + p.c_tau * w * w)


def _bounds(base: DCMotorPlant, cands: Sequence[Candidate], torque: float) -> tuple[np.ndarray, np.ndarray]:
    lo, hi = zip(*(c.bounds(base, torque) for c in cands), strict=True)
    return np.concatenate(lo), np.concatenate(hi)


def _starts(base: DCMotorPlant, cands: Sequence[Candidate]) -> list[np.ndarray]:
    """Starting vectors: the first start of every candidate, varied one candidate at a time."""
    first = [c.starts(base)[0] for c in cands]
    out = [np.concatenate(first)]
    for j, c in enumerate(cands):
        for s in c.starts(base)[1:]:
            out.append(np.concatenate([*first[:j], s, *first[j + 1:]]))
    return out


def _uncertainty(jac: np.ndarray, resid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    m, n = jac.shape
    s2 = float(np.einsum("i,i", resid, resid)) / max(m - n, 1)
    try:
        cov = np.linalg.pinv(np.einsum("ij,ik->jk", jac, jac)) * s2
    except np.linalg.LinAlgError:
        return np.full(n, np.inf), np.eye(n)
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = cov / np.outer(sd, sd)
    corr = np.where(np.isfinite(corr), corr, 0.0)
    np.fill_diagonal(corr, 1.0)
    return np.where(sd > 0, sd, np.inf), corr


def _gauss_newton(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                  iterations: int = 2) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bounded Gauss-Newton for (nearly) linear-in-parameter residuals: a few ``lsq_linear`` steps
    with a forward-difference Jacobian. Returns (x, residual at x, Jacobian)."""
    jac = np.zeros((0, x.size))
    for _ in range(iterations):
        r0 = fun(x)
        h = 1e-6 * np.maximum(np.abs(x), 1e-3 * (hi - lo))
        jac = np.column_stack([(fun(x + h[j] * np.eye(x.size)[j]) - r0) / h[j] for j in range(x.size)])
        x = _bounded_linear(jac, jac @ x - r0, lo, hi)
    return x, fun(x), jac


def _bounded_linear(a: np.ndarray, b: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """argmin |a x - b| within bounds; few columns: normal equations by ``einsum`` (no threaded BLAS on a
    tall matrix), falling back to ``lsq_linear`` when a bound is active."""
    ata = np.einsum("ij,ik->jk", a, a)
    atb = np.einsum("ij,i->j", a, b)
    try:
        x = np.linalg.solve(ata, atb)
    except np.linalg.LinAlgError:
        x = np.full(a.shape[1], np.nan)
    if np.all(np.isfinite(x)) and np.all(x >= lo) and np.all(x <= hi):
        return np.asarray(x)
    if a.shape[1] == 1:
        return np.clip(np.nan_to_num(x, nan=float(lo[0])), lo, hi)
    return np.asarray(lsq_linear(a, b, bounds=(lo, hi)).x)


def _levenberg_marquardt(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                         max_nfev: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Bounded (projected) Levenberg-Marquardt for a few parameters on a tall residual; normal
    equations by ``einsum``. Returns (x, residual at x, Jacobian at x)."""
    r = fun(x)
    cost, lam, nfev = float(np.einsum("i,i", r, r)), 1e-3, 1
    jac = np.zeros((r.size, x.size))
    while nfev < max_nfev:
        h = 1e-6 * np.maximum(np.abs(x), 1e-3 * (hi - lo))
        jac = np.column_stack([(fun(np.minimum(x + h[j] * np.eye(x.size)[j], hi)) - r) / h[j] for j in range(x.size)])
        nfev += x.size
        ata, g = np.einsum("ij,ik->jk", jac, jac), np.einsum("ij,i->j", jac, r)
        improved, done = False, False
        while nfev < max_nfev and lam < 1e8:
            step = np.linalg.solve(ata + lam * np.diag(np.diag(ata) + 1e-30), -g)
            xn = np.clip(x + step, lo, hi)
            rn = fun(xn)
            nfev += 1
            cn = float(np.einsum("i,i", rn, rn))
            if np.isfinite(cn) and cn < cost:
                improved, lam = True, max(lam / 5.0, 1e-9)
                done = bool(cost - cn < 1e-7 * cost or np.all(np.abs(xn - x) <= 1e-7 * (hi - lo)))
                x, r, cost = xn, rn, cn
                break
            lam *= 5.0
        if not improved or done:
            break
    return x, r, jac


def _solve(fun: Callable[[np.ndarray], np.ndarray], base: DCMotorPlant, cands: Sequence[Candidate],
           starts: list[np.ndarray], max_nfev: int | None, torque: float, linear: bool = False, lm: bool = True
           ) -> Estimate:
    """Linear: Gauss-Newton; else the best of the starts by projected Levenberg-Marquardt (``lm``) or
    scipy ``least_squares`` (trust-region reflective); ``torque`` [N m]: :func:`peak_torque` (the boxes)."""
    lo, hi = _bounds(base, cands, torque)
    names = tuple(f"{c.name}.{k}" for c in cands for k in c.keys)
    if linear and starts:
        x, r, jac = _gauss_newton(fun, np.clip(starts[0], lo, hi), lo, hi)
        sd, corr = _uncertainty(jac, r)
        return Estimate(assemble(base, cands, x), names, x, sd, corr, 0.5 * float(np.einsum("i,i", r, r)))
    best: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None
    for x0 in starts:
        if lm:
            sol = _levenberg_marquardt(fun, np.clip(x0, lo, hi), lo, hi, max_nfev or 100)
        else:
            ls = least_squares(fun, np.clip(x0, lo, hi), bounds=(lo, hi), x_scale="jac", method="trf",
                               max_nfev=max_nfev, ftol=1e-6, xtol=1e-6, gtol=1e-8)
            sol = (ls.x, ls.fun, ls.jac)
        if best is None or np.einsum("i,i", sol[1], sol[1]) < np.einsum("i,i", best[1], best[1]):
            best = sol
    if best is None:  # no start given: nothing to fit
        return Estimate(base, (), np.zeros(0), np.zeros(0), np.zeros((0, 0)), 0.0)
    x, r, jac = best
    sd, corr = _uncertainty(jac, r)
    return Estimate(assemble(base, cands, x), names, x, sd, corr, 0.5 * float(np.einsum("i,i", r, r)))


def _residuals(plant: DCMotorPlant, log: Log, view: Callable[[np.ndarray], np.ndarray]
               ) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """One-step residuals of ``plant`` per equation (N-1,) and their row index, the torque equation's through
    ``view`` (:func:`_torque_view`)."""
    r = one_step(plant, log)
    return r.idx, {eq: view(r.equation(eq)) if eq == "mechanical" else r.equation(eq) for eq in EQUATIONS}


def _torque_view(plant: DCMotorPlant, log: Log) -> Callable[[np.ndarray], np.ndarray]:
    """The torque residual seen as the speed error it causes (module doc), at ``plant``'s rotor time constant over
    the logged speeds; a steady-state sweep's as it is."""
    if log.kind is not LogKind.TIME_SERIES:
        return lambda y: y
    tau = rotor_tau(plant.params, log.omega)
    return lambda y: speed_view(y, log.dt, tau)


def equation_scales(plant: DCMotorPlant, log: Log, rows: np.ndarray) -> dict[str, float]:
    """RMS of each one-step equation residual of ``plant`` on ``rows`` (boolean mask over residual index), the torque
    equation's as :func:`equation_error_fit` sees it."""
    idx, res = _residuals(plant, log, _torque_view(plant, log))
    return {eq: max(float(np.sqrt(np.mean(res[eq][rows[idx]] ** 2))), 1e-12) for eq in EQUATIONS}


def equation_error_fit(base: DCMotorPlant, cands: Sequence[Candidate], log: Log, rows: np.ndarray,
                       scales: dict[str, float]) -> Estimate:
    """Fit ``cands`` on the one-step residuals at ``rows`` (bool mask (N,)), equations scaled by ``scales``, the
    torque equation seen through the base plant's view (module doc: one filter for every trial)."""
    view = _torque_view(base, log)

    def fun(theta: np.ndarray) -> np.ndarray:
        idx, res = _residuals(assemble(base, cands, theta), log, view)
        keep = rows[idx]
        out = np.concatenate([res[eq][keep] / scales[eq] for eq in EQUATIONS])
        return np.where(np.isfinite(out), out, 1e6)

    return _solve(fun, base, cands, _starts(base, cands), max_nfev=60, torque=peak_torque(base, log),
                  linear=all(c.linear for c in cands))


def free_run_errors(plant: DCMotorPlant, log: Log, samples: np.ndarray, noise: dict[str, float],
                    segment_s: float) -> np.ndarray:
    """Free-run errors at ``samples`` (bool mask (N,)), each channel divided by its noise level, stacked; a plant
    too stiff to free-run (a trial parameter vector gone sharp) errs by 1e6 everywhere, as a diverging one does."""
    try:
        fr = free_run(plant, log, segment_s)
    except SolverError:
        return np.full(len(CHANNELS) * int(np.sum(samples[run_rows(log, segment_s)])), 1e6)
    keep = samples[fr.idx]
    return np.concatenate([(getattr(log, ch)[fr.idx][keep] - fr.channel(ch)[keep]) / noise[ch] for ch in CHANNELS])


def free_run_fit(start: Estimate, cands: Sequence[Candidate], base: DCMotorPlant, log: Log, samples: np.ndarray,
                 noise: dict[str, float], segment_s: float, max_nfev: int = 40,
                 also: Sequence[np.ndarray] = ()) -> Estimate:
    """Refine ``start`` by minimising the free-run errors at ``samples``; ``also``: more starting points (the best
    refined is taken)."""

    def fun(theta: np.ndarray) -> np.ndarray:
        return free_run_errors(assemble(base, cands, theta), log, samples, noise, segment_s)

    return _solve(fun, base, cands, [start.values, *also], max_nfev=max_nfev, torque=peak_torque(base, log), lm=False)
