"""The point-by-point diagnosis (:func:`diagnose_points`): which effect is missing, which constant is wrong, on a log
the dynamic check cannot free-run (steady-state sweeps, ESC rigs, flight logs; :mod:`ocp.identify.steady` has the
equations' residuals, the fits and the maps it uses).

The greedy forward selection of :mod:`ocp.identify.diagnose` on the point residuals: each candidate that acts on a
checked equation and needs no time (never a lag, delay, ``J`` or ``L``) is fitted by bounded least squares, jointly
with those already chosen (a static map has few points: a compromise fit of one must not hide the next;
``thrust_asymmetry`` is fitted with ``c_f`` free, :data:`PARTNERS`, and must then beat ``c_f`` alone too), on the
training rows (every ``holdout_every``-th held out), scored by the held-out combined error
``E = sqrt(mean_eq (rms_eq / noise_eq)^2)``, and accepted when it improves ``E`` by at least ``min_improvement``
while ``E > noise_floor``. A constant so adopted is named only beyond ``tolerance`` of its nominal value; within it,
the plant takes it as a calibration (``calibration``, as the dynamic check reports it). Candidates whose held-out
error is within the held-out points' sampling scatter of the adopted one's (:func:`_margin`) are reported as its
rivals (``ambiguous``). Then each named item but the last is tested again beside the others (:func:`_backward`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ocp.errors import ParameterError
from ocp.identify.candidates import Candidate, all_candidates, candidate
from ocp.identify.coverage import blind_spots
from ocp.identify.equations import EquationStatus, allowed, checked, noise, residuals, statuses
from ocp.identify.explain import calibration_row, won_at
from ocp.identify.result import DiagnoseOptions, DiagnoseResult, RankEntry, Round, Score, finite
from ocp.identify.signs import check_point_signs
from ocp.identify.steady import ROUTE, UNITS, direction_maps, fit_candidates, score
from ocp.logs import Log
from ocp.model.plant import DCMotorPlant


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
    ref, margin = base * (1.0 - best.entry.improvement), _margin(opt, held)
    return [_rival(best, t, base, f"{t.entry.name} instead of {best.entry.name} fits the held-out points as well "
                                  f"({base * (1.0 - t.entry.improvement):.3g} vs {ref:.3g} noise units; within "
                                  f"{100 * margin:.1f} % or both within the noise floor {opt.noise_floor:g}): "
                                  "this log cannot tell them apart")
            for t in tries if t is not best and t.entry.significant
            and base * (1.0 - t.entry.improvement) <= max(ref * (1.0 + margin), opt.noise_floor)]


def _rival(best: _Try, other: _Try, base: float, reason: str) -> dict[str, Any]:
    """An ``ambiguous`` entry: the adopted candidate, its rival, their held-out scores [noise units] and why."""
    return {"adopted": best.entry.name, "alternative": other.entry.name,
            "score": base * (1.0 - best.entry.improvement),
            "alternative_score": base * (1.0 - other.entry.improvement), "reason": reason}


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
    return [_rival(best, other, base, "on this log the current never opposes the command, the only rows where a "
                                      "brush drop (against the current) and a driver dead band (against the "
                                      f"command) differ: it cannot tell {best.entry.name} from {other.entry.name}")]


def _calibrated(plant: DCMotorPlant, fitted: DCMotorPlant, cand: Candidate, tol: float) -> dict[str, Any]:
    """A constant's entry in ``calibration`` (the dynamic check's row, :func:`.explain.calibration_row`): nominal (in
    ``plant``), fitted (in ``fitted``), relative change, unit, and whether it is beyond the tolerance ``tol`` (named).
    The plant takes the fitted value (``applied``); a constant the sweep's equations cannot judge is no candidate
    (:func:`pool`) and has no row, so none is ``unresolved`` (nor has an ``apparent`` value) or held ``as_given``, and
    no box is widened (``slack``)."""
    nominal, fit_ = (float(cand.values(p)[cand.param_key]) for p in (plant, fitted))
    x = fit_ / nominal - 1.0 if nominal else math.inf
    return calibration_row(nominal, fit_, x, None, cand.units()[cand.param_key], x, abs(x) > tol, abs(x) <= tol)


def _backward(plant: DCMotorPlant, log: Log, chosen: list[Candidate], verdict: list[str],
              text: tuple[list[str], dict[str, str]], rows: tuple[np.ndarray, np.ndarray], nz: dict[str, float],
              opt: DiagnoseOptions) -> DCMotorPlant:
    """Each named item but the last adopted, tested again beside all the others (the dynamic check's backward step,
    :func:`.select.select`): refitted without it on the training points, the held-out score must be worse by
    ``min_improvement``, else it is dropped from ``chosen`` and ``verdict`` (in place) and its sentence in ``text``
    (the explanations, and each named item's sentence in them) replaced by why: an early greedy pick the later
    ones explain (a thrust asymmetry taken for a force offset's reverse side: proving ground sweep 55). Returns the
    plant of what is left, fitted on the training points."""
    train, test = rows
    r0 = residuals(plant, log, tuple(nz))
    scale = {eq: max(float(np.sqrt(np.mean(r0[eq][train] ** 2))), 1e-12) for eq in nz}
    full = fit_candidates(plant, chosen, log, train, scale).plant
    kept = score(full, log, test, nz).combined
    for name in verdict[:-1]:
        rest = [c for c in chosen if c.name != name]
        without = fit_candidates(plant, rest, log, train, scale).plant
        dropped = score(without, log, test, nz).combined
        if kept <= (1.0 - opt.min_improvement) * dropped:
            continue
        chosen[:] = rest
        verdict.remove(name)
        text[0].remove(text[1][name])
        text[0].append(f"{name} is not named: adopted in an early round, it no longer wins on held-out points "
                       f"beside {', '.join(verdict)}")
        full, kept = without, dropped
    return full


def _final(plant: DCMotorPlant, final: DCMotorPlant, constants: list[Candidate], verdict: list[str],
           calibration: dict[str, dict[str, Any]],
           text: tuple[list[str], dict[str, str], dict[str, str]], tol: float) -> None:
    """``calibration`` and the named constants' sentences (``text``: the explanations, each named item's sentence in
    them, and each named constant's evidence from its round) as the ``final`` model carries them, in
    place, as the dynamic check quotes them (:func:`.explain.verdict_sentence`): later rounds refit the constants
    chosen before them, and the backward step refits all (a constant it drops goes back to ``plant``'s value). A
    constant that moved more than a point since its round also gives that round's value (:func:`.explain.won_at`).
    On the proving ground's sweeps 0..199 (``bench/pg_sweeps.py``) 11 tables were more than a point off the final
    plant, in 9 of them further from the drawn error (55: ``c_f`` +38.9 % in its round, +49.3 % final, +49.9 %
    drawn)."""
    explanations, said, won = text
    for c in constants:
        x0 = calibration[c.param_key]["relative"]
        calibration[c.param_key] = {**_calibrated(plant, final, c, tol), "named": c.name in verdict}
        if c.name in verdict and c.name in won:  # (one the backward step dropped has its sentence replaced)
            cal = calibration[c.param_key]
            moved = won_at(cal["nominal"], cal["relative"], x0, cal["unit"])
            sentence = _sentence(c.explain(plant, final).rstrip(".") + moved, won[c.name])
            explanations[explanations.index(said[c.name])] = sentence
            said[c.name] = sentence


def _sentence(text: str, evidence: str) -> str:
    """An item's explanation and the evidence that named it, one sentence each."""
    return f"{text.rstrip('.')}. {evidence}"


def diagnose_points(plant: DCMotorPlant, log: Log, options: DiagnoseOptions | None = None) -> PointDiagnosis:
    """Rank the time-free candidates on the checkable equations, point by point (module doc)."""
    opt = options or DiagnoseOptions()
    eqs = checked(log)
    check_point_signs(plant, log, eqs)
    if not eqs:
        return PointDiagnosis([], [], plant, {}, ["no equation can be checked on this log"],
                              equations=statuses(log), maps=direction_maps(log), kind=log.kind.value,
                              notes=log.notes)
    nz = noise(log, eqs, plant)
    test = np.arange(log.n) % opt.holdout_every == opt.holdout_every - 1
    rows = (~test, test)
    current, explanations, rounds = plant, [], []
    said: dict[str, str] = {}  # a named item's sentence in explanations
    won: dict[str, str] = {}  # a named constant's sentence's evidence, from its round

    def name_it(name: str, text: str, cand: Candidate | None = None, evidence: str = "") -> None:
        verdict.append(name)
        explanations.append(text)
        said[name] = text
        if cand is not None and cand.is_param:
            won[name] = evidence

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
                why = f"Fitted with {best.entry.name}; held-out error down {100 * gain:.0f} % against it alone."
                name_it(best.cands[0].name, _sentence(best.cands[0].explain(current, best.plant), why), best.cands[0],
                        why)
        current = best.plant
        chosen += best.cands
        if best.cands[-1].is_param and not calibration[best.cands[-1].param_key]["named"]:
            explanations.append(f"{best.entry.explanation} Within the {100 * opt.tolerance:g} % tolerance: "
                                "calibrated, not named.")
            continue
        rivals = _rivals(best, tries, base.combined, opt, held)
        ambiguous += rivals + [a for a in _sign_alike(best, tries, log, base.combined)
                               if a["alternative"] not in {r["alternative"] for r in rivals}]
        why = f"Held-out error down {100 * best.entry.improvement:.0f} %."
        name_it(best.entry.name, _sentence(best.entry.explanation, why), best.cands[-1], why)
    if len(verdict) > 1:
        current = _backward(plant, log, chosen, verdict, (explanations, said), rows, nz, opt)
    _final(plant, current, [c for c in cands if c.is_param and c.param_key in calibration], verdict, calibration,
           (explanations, said, won), opt.tolerance)
    fitted_maps = {"thrust_ratio_reverse_to_forward": finite(r) if (r := thrust_ratio(current, log)) else None}
    return PointDiagnosis(verdict, rounds, current, nz, explanations, calibration=calibration, ambiguous=ambiguous,
                          tolerance=opt.tolerance, blind_spots=blind_spots(log, verdict, rows=True),
                          equations=statuses(log), maps=direction_maps(log),
                          kind=log.kind.value, notes=log.notes, fitted_maps=fitted_maps)
