"""Point-by-point model checks where the dynamic check (free run under the armature voltage) cannot
run: steady-state sweeps, ESC rigs and flight logs (supply-side electrics, no thrust).

Every checkable equation (:mod:`ocp.identify.equations`) is confronted with the log row by row and
broken down by direction (``w > 0`` forward, ``w < 0`` reverse). ``diagnose`` is the greedy forward
selection of :mod:`ocp.identify.diagnose` on those residuals: each candidate that acts on a checked
equation and needs no time (never a lag, delay, ``J`` or ``L``) is fitted by bounded least squares,
jointly with those already chosen (a static map has few points: a compromise fit of one must not hide
the next; ``thrust_asymmetry`` is fitted with ``c_f`` free, :data:`PARTNERS`, and must then beat ``c_f``
alone too), on the training rows (every ``holdout_every``-th held out), scored by the held-out combined error
``E = sqrt(mean_eq (rms_eq / noise_eq)^2)``, and accepted when it improves ``E`` by at least
``min_improvement`` while ``E > noise_floor``. A constant so adopted is named only beyond ``tolerance`` of its
nominal value; within it, the plant takes it as a calibration (``calibration``, as the dynamic check reports it).
Candidates whose held-out error is within the held-out points' sampling scatter of the adopted one's
(:func:`_margin`) are reported as its rivals (``ambiguous``).

The direction maps are plant-free least squares per direction: thrust ``F = c w|w|`` gives the
forward and reverse thrust coefficients and their ratio (reverse / forward); torque ``tau = c w|w|``
or supply power ``P = p0 + c |w|^3`` likewise.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np
from scipy.optimize import least_squares

from ocp.errors import ParameterError
from ocp.identify.candidates import Candidate, all_candidates, candidate
from ocp.identify.diagnose import DiagnoseOptions, DiagnoseResult, RankEntry, Round, Score, finite
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


def pool(log: Log, opt: DiagnoseOptions, plant: DCMotorPlant) -> list[Candidate]:
    """The candidates :func:`diagnose_points` may name on ``log`` (time effects never; see equations.allowed)."""
    if opt.candidates is not None:  # asked for by name: refused by name when this log cannot judge it
        cands = [candidate(n) for n in opt.candidates]
        for c in cands:
            if not allowed(c.name, c.channel, log):
                raise ParameterError(c.name, f"cannot be judged on this log (checked: {list(checked(log))}; "
                                             "time effects never on a sweep or without the armature voltage)")
    else:
        cands = all_candidates(opt.include_params)
    present = {e.name for e in plant.effects}
    out = [c for c in cands if c.name not in present and allowed(c.name, c.channel, log)]
    if opt.candidates is None and {"mechanical", "electrical"} <= set(checked(log)) \
            and any(c.name == "param:k" for c in out):
        # k_t = k_e in SI: where both equations judge the motor constant, it is corrected as one (as the dynamic
        # check does); k_t alone mimicked a propeller drag error on a sweep (i ~ w^2 there)
        out = [c for c in out if c.name not in ("param:k_t", "param:k_e")]
    return out


@dataclass(frozen=True)
class PointDiagnosis(DiagnoseResult):
    """:class:`DiagnoseResult` of the point-by-point route, with the equations and direction maps."""

    equations: tuple[EquationStatus, ...] = ()
    maps: dict[str, Any] = field(default_factory=dict)
    kind: str = "steady-state"
    notes: tuple[str, ...] = ()
    fitted_maps: dict[str, Any] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        d = super().to_dict()
        d.update(route=ROUTE, kind=self.kind, units=dict(UNITS), equations=[e.to_dict() for e in self.equations],
                 maps=self.maps, fitted_maps=self.fitted_maps, notes=list(self.notes))
        return d


def thrust_ratio(plant: DCMotorPlant, log: Log) -> float | None:
    """Reverse/forward thrust coefficient ``(c_f + dc_f) / c_f`` of a plant with a thrust asymmetry, both
    coefficients refitted on every row of the thrust equation (the forward one is released even when its
    correction was not significant: the ratio needs both estimated). None without an asymmetry."""
    if not any(e.name == "thrust_asymmetry" for e in plant.effects) or "thrust" not in checked(log):
        return None
    cands = [candidate("param:c_f"), candidate("thrust_asymmetry")]
    r0 = residuals(plant, log, ("thrust",))["thrust"]
    f = fit_candidates(plant, cands, log, np.ones(log.n, dtype=bool),
                       {"thrust": max(float(np.sqrt(np.mean(r0**2))), 1e-12)})
    c_f, dc_f = float(f.values[0]), float(f.values[1])
    return (c_f + dc_f) / c_f


#: an asymmetry is a ratio between the directions: it is fitted with the forward coefficient free (a nominal
#: c_f between the true forward and reverse ones hides both when each is tried alone)
PARTNERS = {"thrust_asymmetry": "param:c_f"}


@dataclass(frozen=True)
class _Try:
    entry: RankEntry
    plant: DCMotorPlant
    cands: tuple[Candidate, ...]  # the candidate, after its partner when it has one


def _try(current: DCMotorPlant, chosen: list[Candidate], cand: Candidate, pool_: list[Candidate], log: Log,
         rows: tuple[np.ndarray, np.ndarray], scale: dict[str, float], nz: dict[str, float], base: Score,
         opt: DiagnoseOptions) -> _Try:
    """Fit ``cand`` (with its partner) jointly with those chosen on the training rows; score it held out."""
    train, test = rows
    extra = tuple(c for c in pool_ if c.name == PARTNERS.get(cand.name) and c not in chosen)
    fitted = fit_candidates(current, [*chosen, *extra, cand], log, train, scale)
    s = score(fitted.plant, log, test, nz)
    imp = 1.0 - s.combined / base.combined if math.isfinite(s.combined) and base.combined > 0 else -math.inf
    ok = imp >= opt.min_improvement and base.combined > opt.noise_floor
    if ok and extra:  # the candidate must earn its place against its partner alone, not borrow the partner's gain
        partner = score(fit_candidates(current, [*chosen, *extra], log, train, scale).plant, log, test, nz)
        ok = 1.0 - s.combined / partner.combined >= opt.min_improvement
    return _Try(RankEntry(cand.name, imp, ok, cand.values(fitted.plant), cand.units(), s.rms,
                          cand.explain(current, fitted.plant)), fitted.plant, (*extra, cand))


def _margin(opt: DiagnoseOptions, held: int) -> float:
    """The relative difference of held-out scores within which two candidates fit equally well: ``ambiguity_margin``
    or two standard errors of an RMS over the ``held`` held-out residuals, ``2 / sqrt(2 held)``, whichever is wider
    (as the dynamic check's :func:`.evidence.scatter`): a sweep of 15 points holds out 5 per equation, and a score
    10 % better there is sampling noise (a brush drop and a driver dead band, alike wherever the motor drives)."""
    return max(opt.ambiguity_margin, 2.0 / math.sqrt(2.0 * max(held, 1)))


def _rivals(best: _Try, tries: list[_Try], base: float, opt: DiagnoseOptions, held: int) -> list[dict[str, Any]]:
    """Other candidates that fit the held-out rows as well as ``best``: held-out score within :func:`_margin` of it,
    or both within the noise (``noise_floor``; ``base`` is the score before this round, in noise units). The sweep
    cannot tell them apart (e.g. Coulomb friction and a viscous ``B`` change at one speed)."""
    out: list[dict[str, Any]] = []
    ref, margin = base * (1.0 - best.entry.improvement), _margin(opt, held)
    for t in tries:
        alt = base * (1.0 - t.entry.improvement)
        if t is not best and t.entry.significant and alt <= max(ref * (1.0 + margin), opt.noise_floor):
            out.append({"adopted": best.entry.name, "alternative": t.entry.name, "score": ref,
                        "alternative_score": alt,
                        "reason": f"{t.entry.name} instead of {best.entry.name} fits the held-out points as well "
                                  f"({alt:.3g} vs {ref:.3g} noise units; within {100 * margin:.1f} % "
                                  f"or both within the noise floor {opt.noise_floor:g}): "
                                  "this log cannot tell them apart"})
    return out


#: pairs a steady log tells apart only on rows where the current opposes the command (a brush drop acts against the
#: current, a driver dead band against the command); a motor driving a load at steady state has none
SIGN_ALIKE = frozenset({"brush_drop", "voltage_deadband"})


def _sign_alike(best: _Try, tries: list[_Try], log: Log, base: float) -> list[dict[str, Any]]:
    """The other of :data:`SIGN_ALIKE` as ``best``'s rival where no row of ``log`` has a current (over 1 % of the
    largest) opposing its command: there the two predict the same rows, whatever their fits' held-out scores (the
    catalogue's brush drop is smooth in the current near zero, so the dead band fitted a sweep's brush drop better
    on the proving ground's sweeps, ``bench/pg_sweeps.py``)."""
    if best.entry.name not in SIGN_ALIKE or "electrical" not in checked(log):  # (the armature's V and i logged)
        return []
    i, v = log.current, log.voltage
    if np.any((np.sign(i) * np.sign(v) < 0) & (np.abs(i) > 0.01 * float(np.max(np.abs(i))))):
        return []
    other = next((t for t in tries if t.entry.name in SIGN_ALIKE - {best.entry.name}), None)
    if other is None:
        return []
    score_of = lambda t: base * (1.0 - t.entry.improvement)  # noqa: E731
    return [{"adopted": best.entry.name, "alternative": other.entry.name, "score": score_of(best),
             "alternative_score": score_of(other),
             "reason": f"on this log the current never opposes the command, the only rows where a brush drop (against "
                       f"the current) and a driver dead band (against the command) differ: it cannot tell "
                       f"{best.entry.name} from {other.entry.name}"}]


def _calibrated(plant: DCMotorPlant, fitted: DCMotorPlant, cand: Candidate, tol: float) -> dict[str, Any]:
    """A constant's entry in ``calibration`` (the dynamic check's keys): nominal (in ``plant``), fitted (in
    ``fitted``), relative change, unit, and whether it is beyond the tolerance ``tol`` (named)."""
    nominal = _value(plant, cand.param_key)
    fit_ = float(cand.values(fitted)[cand.param_key])
    x = fit_ / nominal - 1.0 if nominal else math.inf
    return {"nominal": nominal, "fitted": fit_, "relative": x, "unit": cand.units()[cand.param_key],
            "named": abs(x) > tol, "within_tolerance": abs(x) <= tol}


def _value(plant: DCMotorPlant, key: str) -> float:
    """Constant ``key`` of ``plant`` (``k``: the motor constant, read as ``k_t``)."""
    return float(getattr(plant.params, "k_t" if key == "k" else key))


def diagnose_points(plant: DCMotorPlant, log: Log, options: DiagnoseOptions | None = None) -> PointDiagnosis:
    """Rank the time-free candidates on the checkable equations, point by point (module doc)."""
    opt = options or DiagnoseOptions()
    eqs = checked(log)
    if not eqs:
        return PointDiagnosis([], [], plant, {}, ["no equation can be checked on this log"],
                              equations=statuses(log), maps=direction_maps(log), kind=log.kind.value,
                              notes=log.notes)
    nz = noise(log, eqs, plant)
    test = np.arange(log.n) % opt.holdout_every == opt.holdout_every - 1
    rows = (~test, test)
    current, explanations, rounds = plant, [], []
    verdict: list[str] = []
    chosen: list[Candidate] = []
    ambiguous: list[dict[str, Any]] = []
    calibration: dict[str, dict[str, Any]] = {}
    cands = pool(log, opt, plant)
    held = int(test.sum()) * len(eqs)
    while len(verdict) < opt.max_effects and len(chosen) < len(cands):
        base = score(current, log, test, nz)
        r0 = residuals(current, log, eqs)
        scale = {eq: max(float(np.sqrt(np.mean(r0[eq][~test] ** 2))), 1e-12) for eq in eqs}
        tries = sorted((_try(current, chosen, c, cands, log, rows, scale, nz, base, opt) for c in cands
                        if c not in chosen), key=lambda t: (-t.entry.improvement, len(t.cands)))
        rounds.append(Round(base, [t.entry for t in tries]))
        best = next((t for t in tries if t.entry.significant), None)  # a paired one may rank first yet fail
        if best is None:
            break
        for c in best.cands:  # a constant: named beyond the tolerance, else a calibration the plant takes
            if c.is_param:
                calibration[c.param_key] = _calibrated(plant, best.plant, c, opt.tolerance)
        if len(best.cands) > 1 and calibration[best.cands[0].param_key]["named"]:
            # the partner (c_f) is named too when it matters on its own
            alone = fit_candidates(current, [*chosen, best.cands[-1]], log, rows[0], scale)
            gain = 1.0 - score(best.plant, log, test, nz).combined / score(alone.plant, log, test, nz).combined
            if gain >= opt.min_improvement:
                verdict.append(best.cands[0].name)
                explanations.append(f"{best.cands[0].explain(current, best.plant)} Fitted with "
                                    f"{best.entry.name}; held-out error down {100 * gain:.0f} % against it alone.")
        current = best.plant
        chosen += best.cands
        if best.cands[-1].is_param and not calibration[best.cands[-1].param_key]["named"]:
            explanations.append(f"{best.entry.explanation} Within the {100 * opt.tolerance:g} % tolerance: "
                                "calibrated, not named.")
            continue
        rivals = _rivals(best, tries, base.combined, opt, held)
        ambiguous += rivals + [a for a in _sign_alike(best, tries, log, base.combined)
                               if a["alternative"] not in {r["alternative"] for r in rivals}]
        verdict.append(best.entry.name)
        explanations.append(f"{best.entry.explanation} Held-out error down {100 * best.entry.improvement:.0f} %.")
    fitted_maps = {"thrust_ratio_reverse_to_forward": finite(r) if (r := thrust_ratio(current, log)) else None}
    return PointDiagnosis(verdict, rounds, current, nz, explanations, calibration=calibration, ambiguous=ambiguous,
                          tolerance=opt.tolerance, equations=statuses(log), maps=direction_maps(log),
                          kind=log.kind.value, notes=log.notes, fitted_maps=fitted_maps)


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
    on no checked equation is refused naming it.
    """
    from ocp.errors import LogError
    from ocp.identify.fit import FitResult

    eqs = checked(log)
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
    return FitResult(plant=f.plant, effects=tuple(c.name for c in cands), stage="equation-error",
                     names=tuple(f"{c.name}.{key}" for c in cands for key in c.keys), values=f.values,
                     stderr=np.where(sd > 0, sd, np.inf), correlation=corr, before=before, after=after,
                     before_equations=before, after_equations=after)
