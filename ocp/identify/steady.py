"""Point-by-point model checks where the dynamic check (free run under the armature voltage) cannot
run: steady-state sweeps, ESC rigs and flight logs (supply-side electrics, no thrust).

Every checkable equation (:mod:`ocp.identify.equations`) is confronted with the log row by row and
broken down by direction (``w > 0`` forward, ``w < 0`` reverse); ``fit`` fits named candidates on every row by
bounded least squares. The diagnosis on those residuals is :mod:`ocp.identify.steady_diagnose`.

The direction maps are plant-free least squares per direction: thrust ``F = c w|w|`` gives the
forward and reverse thrust coefficients and their ratio (reverse / forward); torque ``tau = c w|w|``
or supply power ``P = p0 + c |w|^3`` likewise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.optimize import least_squares

from ocp.identify.candidates import Candidate, candidate
from ocp.identify.equations import (
    TIME_EFFECTS,
    UNITS,
    EquationStatus,
    allowed,
    checked,
    measured_side,
    model_load,
    noise,
    power_residual,
    rates,
    residuals,
    statuses,
)
from ocp.identify.estimate import assemble, peak_torque
from ocp.identify.result import Score, finite
from ocp.identify.signs import check_point_signs
from ocp.logs import Log, LogKind
from ocp.model.plant import DCMotorPlant

if TYPE_CHECKING:
    from ocp.identify.fit import FitResult

ROUTE = "point-by-point"
MAX_POINTS = 2000  # per-row arrays in the answer for sweeps up to this many rows


def directions(log: Log) -> dict[str, np.ndarray]:
    """Masks (N,) of forward (``w > 0``), reverse (``w < 0``) rows and those at rest."""
    return {"forward": log.omega > 0, "reverse": log.omega < 0, "at rest": log.omega == 0}


def _coef(x: np.ndarray, y: np.ndarray) -> float | None:
    """Least-squares ``c`` of ``y = c x`` (None without signal)."""
    d = float(np.dot(x, x))
    return float(np.dot(x, y)) / d if d > 0 else None


def direction_maps(log: Log) -> dict[str, Any]:
    """Plant-free per-direction coefficients (module doc); ``ratio`` = reverse / forward."""
    w, out = log.omega, {}
    masks = directions(log)
    series: dict[str, tuple[np.ndarray, np.ndarray, str]] = {}
    if log.has("thrust"):
        series["thrust"] = (w * np.abs(w), log.thrust, "N s^2/rad^2")
    if log.torque is not None:
        series["torque"] = (w * np.abs(w), log.torque, "N m s^2/rad^2")
    if log.electrical == "supply" and log.has("voltage") and log.has("current"):
        p = log.voltage * log.current
        rest = masks["at rest"]
        p0 = float(np.median(p[rest])) if rest.any() else 0.0
        series["power"] = (np.abs(w) ** 3, p - p0, "W s^3/rad^3")
    for name, (x, y, unit) in series.items():
        fwd = _coef(x[masks["forward"]], y[masks["forward"]])
        rev = _coef(x[masks["reverse"]], y[masks["reverse"]])
        ratio = rev / fwd if fwd and rev is not None else None
        out[name] = {"forward": None if fwd is None else finite(fwd), "reverse": None if rev is None else finite(rev),
                     "ratio_reverse_to_forward": None if ratio is None else finite(ratio), "units": unit}
    return out


def _stats(r: np.ndarray, scale: float) -> dict[str, Any]:
    if not r.size:
        return {"n": 0, "rms": None, "mean": None, "relative_rms": None}
    rms = float(np.sqrt(np.mean(r * r)))
    return {"n": int(r.size), "rms": finite(rms), "mean": finite(float(np.mean(r))),
            "relative_rms": finite(rms / scale) if scale > 0 else None}


def by_direction(log: Log, res: dict[str, np.ndarray], measured: dict[str, np.ndarray]) -> dict[str, Any]:
    """Equation -> direction -> residual statistics (n, rms, mean, rms relative to the measured side)."""
    out: dict[str, Any] = {}
    for eq, r in res.items():
        y = measured[eq]
        out[eq] = {d: _stats(r[m], float(np.sqrt(np.mean(y[m] ** 2))) if m.any() else 0.0)
                   for d, m in directions(log).items() if d != "at rest"}
    return out


@dataclass(frozen=True)
class Fitted:
    plant: DCMotorPlant
    values: np.ndarray
    jac: np.ndarray
    resid: np.ndarray


def fit_candidates(base: DCMotorPlant, cands: Sequence[Candidate], log: Log, rows: np.ndarray,
                   scale: dict[str, float]) -> Fitted:
    """Bounded least squares of the candidates' parameters on the stacked scaled residuals at ``rows``; torque-valued
    boxes reach the motor's torque in the log (:func:`.estimate.peak_torque`: the catalogue's 0.1 N m held a 500 W
    sweep's 0.4 N m Coulomb friction at the box, and its diagnosis named ``k_t``, ``c_tau`` and Stribeck instead)."""
    eqs = tuple(scale)
    torque = peak_torque(base, log)
    lo = np.concatenate([c.bounds(base, torque)[0] for c in cands])
    hi = np.concatenate([c.bounds(base, torque)[1] for c in cands])

    def fun(theta: np.ndarray) -> np.ndarray:
        r = residuals(assemble(base, cands, theta), log, eqs)
        out = np.concatenate([r[eq][rows] / scale[eq] for eq in eqs])
        return np.where(np.isfinite(out), out, 1e6)

    best = None
    for x0 in _starts(base, cands):
        sol = least_squares(fun, np.clip(x0, lo, hi), bounds=(lo, hi), x_scale="jac", method="trf",
                            max_nfev=200, ftol=1e-10, xtol=1e-10, gtol=1e-12)
        if best is None or sol.cost < best.cost:
            best = sol
    if best is None:  # _starts always gives one: a programming error, not bad input
        raise RuntimeError("no starting point")
    return Fitted(assemble(base, cands, best.x), best.x, best.jac, best.fun)


def _starts(base: DCMotorPlant, cands: Sequence[Candidate]) -> list[np.ndarray]:
    first = [c.starts(base)[0] for c in cands]
    out = [np.concatenate(first)]
    for j, c in enumerate(cands):
        out += [np.concatenate([*first[:j], s, *first[j + 1:]]) for s in c.starts(base)[1:]]
    return out


def score(plant: DCMotorPlant, log: Log, rows: np.ndarray, nz: dict[str, float]) -> Score:
    """Held-out RMS per equation at ``rows`` and the combined ``E`` (module doc)."""
    r = residuals(plant, log, tuple(nz))
    rms = {eq: float(np.sqrt(np.mean(r[eq][rows] ** 2))) for eq in nz}
    comb = math.sqrt(sum((rms[eq] / nz[eq]) ** 2 for eq in nz) / len(nz))
    return Score(rms, comb if math.isfinite(comb) else math.inf)


@dataclass(frozen=True)
class PointCheck:
    """Where the model fails, equation by equation and direction by direction (no simulation)."""

    kind: str
    equations: tuple[EquationStatus, ...]
    rms: dict[str, float]
    mean: dict[str, float]
    noise: dict[str, float]
    breakdown: dict[str, Any]
    maps: dict[str, Any]
    points: dict[str, Any]
    notes: tuple[str, ...]
    drive: dict[str, float | None]

    def to_dict(self) -> dict[str, Any]:
        return {
            "kind": self.kind, "route": ROUTE, "notes": list(self.notes),
            "equations": [e.to_dict() for e in self.equations],
            "free_run": {"label": "not simulated: the log has no armature voltage to drive the model with, or is a "
                                  "steady-state sweep", "rms": {}, "max": {}, "units": {}},
            "one_step": {"label": "equation residuals point by point (measured - model)",
                         "rms": {k: finite(v) for k, v in self.rms.items()},
                         "mean": {k: finite(v) for k, v in self.mean.items()},
                         "units": {k: UNITS[k] for k in self.rms}},
            "noise": {k: finite(v) for k, v in self.noise.items()},
            "breakdown": self.breakdown, "correlation": {}, "maps": self.maps, "points": self.points,
            "drive": self.drive,
        }


def check_points(plant: DCMotorPlant, log: Log) -> PointCheck:
    """Residuals of every checkable equation, by direction, the direction maps and (sweeps) every point."""
    eqs = checked(log)
    check_point_signs(plant, log, eqs)
    res = residuals(plant, log, eqs)
    meas = measured_side(log, plant, eqs)
    drive: dict[str, float | None] = {}
    if "power" in eqs:
        p = plant.params
        tau = model_load(plant, log) + p.J * rates(log)[0]
        _, eta, p0 = power_residual(log.voltage * log.current, tau * log.omega + p.R * (tau / p.k_t) ** 2)
        drive = {"efficiency": finite(eta), "idle_power_W": finite(p0)}
    points: dict[str, Any] = {}
    if log.kind is LogKind.STEADY_STATE and log.n <= MAX_POINTS:
        points = {"omega": [float(v) for v in log.omega],
                  "measured": {eq: [finite(float(v)) for v in meas[eq]] for eq in eqs},
                  "model": {eq: [finite(float(v)) for v in meas[eq] - res[eq]] for eq in eqs}}
    return PointCheck(log.kind.value, statuses(log), {eq: float(np.sqrt(np.mean(r * r))) for eq, r in res.items()},
                      {eq: float(np.mean(r)) for eq, r in res.items()}, noise(log, eqs, plant) if eqs else {},
                      {"direction": by_direction(log, res, meas)}, direction_maps(log), points, log.notes, drive)


def fit_points(plant: DCMotorPlant, log: Log, names: Sequence[str]) -> FitResult:
    """Add the named candidates and fit them on every row of the checkable equations (point by point).

    Before/after errors are the equation residual RMS [equation unit]; a candidate that needs time or acts
    on no checked equation is refused naming it. The fit is adopted only where it lowers the residuals (combined
    over the equations, each in units of its starting RMS: :func:`.fit.adoption_note`); else the starting plant.
    """
    from ocp.errors import LogError
    from ocp.identify.fit import FitResult, adoption_note

    eqs = checked(log)
    check_point_signs(plant, log, eqs)
    cands = [candidate(n) for n in dict.fromkeys(names)]
    for c in cands:
        if not allowed(c.name, c.channel, log):
            why = "it needs time (lags, delays, J, L)" if c.name in TIME_EFFECTS else (
                f"it acts on the {c.channel} equation, which this log cannot check")
            raise LogError("effects", f"{c.name} cannot be fitted on this log: {why}; checked: {list(eqs)}")
    every = np.ones(log.n, dtype=bool)
    r0 = residuals(plant, log, eqs)
    scale = {eq: max(float(np.sqrt(np.mean(r0[eq] ** 2))), 1e-12) for eq in eqs}
    f = fit_candidates(plant, cands, log, every, scale)
    m, k = f.jac.shape
    s2 = float(np.dot(f.resid, f.resid)) / max(m - k, 1)
    cov = np.linalg.pinv(f.jac.T @ f.jac) * s2
    sd = np.sqrt(np.clip(np.diag(cov), 0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        corr = np.nan_to_num(cov / np.outer(sd, sd))
    np.fill_diagonal(corr, 1.0)
    before = {eq: float(np.sqrt(np.mean(r ** 2))) for eq, r in r0.items()}
    after = {eq: float(np.sqrt(np.mean(r ** 2))) for eq, r in residuals(f.plant, log, eqs).items()}
    e_start, e_fit = (float(np.sqrt(np.mean([(e[eq] / scale[eq]) ** 2 for eq in eqs]))) for e in (before, after))
    note = adoption_note(e_start, e_fit, "fits this log's equations", "of the starting residuals")
    return FitResult(plant=f.plant if note is None else plant, adopted=note is None, note=note,
                     effects=tuple(c.name for c in cands), stage="equation-error",
                     names=tuple(f"{c.name}.{key}" for c in cands for key in c.keys), values=f.values,
                     stderr=np.where(sd > 0, sd, np.inf), correlation=corr, before=before, after=after,
                     before_equations=before, after_equations=after)
