"""Design the experiment that settles it: an excitation chosen to SEPARATE rival explanations of a log.

When :func:`ocp.identify.diagnose` cannot tell explanations apart on a log (``ambiguous``: Coulomb friction
or a viscous ``B`` change on one operating speed, ...) or an effect cannot show in it (no reversal, no time
at low speed, one speed only, one voltage magnitude), :func:`design` proposes a mission for the optimiser whose
command makes the rivals' predicted outputs differ the most relative to the log's noise, and says how well it
will separate them.

**Rivals.** Ambiguity: the verdict, and the verdict with each ambiguous item swapped for its alternative,
each fitted to the log (:func:`ocp.identify.fit`). Coverage gaps: the diagnosed plant, and the same plant with
each effect the log cannot show at a *probe* size (:data:`PROBES`, relative to the plant's torque, thrust
and voltage at the top speed): "would this experiment reveal a 5 % Coulomb friction?"; where hardly a moving row is slow
enough to show an angle ripple of 64 periods/rev (:func:`.coverage.coverage`), such a ripple. ``rivals`` in
:class:`DesignOptions` names the candidate sets instead.

**Criterion** (:mod:`.separation`: T-optimal discrimination, Atkinson & Fedorov 1975, linearised). Every
candidate excitation (:mod:`.excite`) is optimised within the limits (:func:`ocp.optimize.solve.optimize`, the
diagnosed plant); a candidate the optimiser cannot run within them is dropped. Every rival is simulated open
loop under the optimised voltage; for each pair, what one rival cannot explain of the other's predicted
speed, current and thrust (in the log's noise units, refitting its own items freely and the other constants
within about the tolerance) is the separation ``z`` [noise standard deviations]. The proposal maximises the
smallest ``z`` over the pairs (the :data:`SHORTLIST` best by the raw difference are scored with the refit);
a likelihood-ratio test then confuses the closest pair with probability ``Phi(-z / 2)``. The same ``z`` on
the given log (its own voltage) says how little it separated them, assuming one rival is the truth; how far each
rival's free run misses the log itself (``current_log_errors``, noise units, as :func:`ocp.identify.fit` reports
it) says whether either is: rivals that differ by a large ``z`` on the log yet miss it alike are both wrong there
(proving ground 6180: ``L`` against a delay, z 2.6e3 on the log, both missing it by 16 noise units).
Rivals are fitted to the log as :func:`ocp.identify.fit` fits, the free-run refinement included: the one-step
start alone fitted ``J`` a sixth of the rig's on a 10 kHz log (6168; the rivals' free runs missed the log by
150 noise units, the diagnosed plant by 1.4).

**Logging.** Where the log is too slow for its electrical time constant (L/R under two samples,
:func:`.regression.slow_armature`), no excitation at its rate checks ``L``: the design says so and advises a
rate (:func:`logging_advice`), whatever else it proposes.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator

from ocp.errors import LogError, ParameterError, ThrustshapeError
from ocp.identify.angle import MAX_PERIODS
from ocp.identify.candidates import candidate
from ocp.identify.coverage import COMMON_GAIN, coverage, open_gaps
from ocp.identify.diagnose import aligned, dynamic
from ocp.identify.excite import Excitation, candidates, mission_for
from ocp.identify.predict import CHANNELS, MAX_STEPS_PER_SAMPLE, SUBSTEPS, noise_levels, substeps
from ocp.identify.resolution import ADVISED_SAMPLES, ARMATURE_SAMPLES, advised_rate, slow_armature
from ocp.identify.result import DiagnoseResult
from ocp.identify.separation import (
    Rival,
    confusion,
    held_on_grid,
    pair_separations,
    with_constant,
    with_effect,
)
from ocp.logs import Log
from ocp.model.effects import plant_to_mapping
from ocp.model.equilibrium import equilibrium
from ocp.model.plant import DCMotorPlant

#: at most this many rivals (the verdict and its closest alternatives, or the user's): the fits (each refined) and
#: the pairs a design separates stay bounded (a 50 Hz log with 16 ambiguities took 228 s with them all)
MAX_RIVALS = 6
#: probe sizes of effects a log cannot show: fraction of the load torque tau_top, thrust F_top, voltage limit
#: V, top speed w_top, c_tau, c_f (the smallest a user of a thruster would want to know about)
PROBES: dict[str, Callable[[dict[str, float]], dict[str, float]]] = {
    "coulomb_friction": lambda s: {"tau_c": 0.05 * s["tau_top"]},
    "stribeck": lambda s: {"tau_s": 0.1 * s["tau_top"], "omega_s": 0.05 * s["w_top"]},
    "drag_asymmetry": lambda s: {"dc_tau": 0.2 * s["c_tau"]},
    "thrust_asymmetry": lambda s: {"dc_f": 0.2 * s["c_f"]},
    "voltage_deadband": lambda s: {"v_db": 0.05 * s["V"]},
    "brush_drop": lambda s: {"v_b": 0.03 * s["V"]},
    # the highest count offered (for a log almost without rows slow enough to show it, :func:`.coverage.coverage`)
    "cogging": lambda s: {"tau_sin": 0.05 * s["tau_top"], "tau_cos": 0.0, "periods": float(MAX_PERIODS)},
}
SHORTLIST = 3  # candidates whose separation is computed with the refit (best raw separations)


class DesignOptions(BaseModel):
    """Knobs of :func:`design`: limits [V, A] (default: the log's own peaks), duration [s] (default: 60
    mechanical time constants within 2..20 s), rival candidate sets (default: from the diagnosis)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    voltage: float | None = Field(default=None, gt=0, le=1e4)
    current: float | None = Field(default=None, gt=0, le=1e4)
    duration_s: float | None = Field(default=None, ge=0.2, le=60.0)
    rivals: tuple[tuple[str, ...], ...] | None = Field(default=None, min_length=2, max_length=MAX_RIVALS)
    time_limit_s: float = Field(default=10.0, gt=0, le=600)  # per candidate optimisation [s]

    @field_validator("rivals")
    @classmethod
    def _known(cls, v: tuple[tuple[str, ...], ...] | None) -> tuple[tuple[str, ...], ...] | None:
        for r in v or ():
            if not r or len(r) > 6:
                raise ValueError("a rival is 1 to 6 effects or param:<key> corrections")
            for name in r:
                try:
                    candidate(name)
                except ThrustshapeError as exc:
                    raise ValueError(f"{name!r}: {exc.reason}") from None
        return v


@dataclass(frozen=True)
class Candidate:
    """One excitation's scores: separation ``z`` per rival pair (after the refit; ``raw`` without it)."""

    name: str
    description: str
    runnable: bool
    note: str
    raw: dict[str, float] = field(default_factory=dict)
    separation: dict[str, float] = field(default_factory=dict)
    rms_ratio: dict[str, float] = field(default_factory=dict)

    @property
    def worst(self) -> float:
        vals = self.separation or self.raw
        return min(vals.values()) if vals and self.runnable else -math.inf

    def to_dict(self) -> dict[str, Any]:
        return {"name": self.name, "description": self.description, "runnable": self.runnable, "note": self.note,
                "separation": self.separation or None, "raw_separation": self.raw, "rms_ratio": self.rms_ratio}


@dataclass(frozen=True)
class DesignResult:
    """The proposal: why an experiment is needed, the rivals, every candidate's scores, the chosen mission."""

    needed: bool
    reasons: list[str]
    coverage: dict[str, Any]
    rivals: list[Rival]
    candidates: list[Candidate]
    chosen: Candidate | None
    mission: dict[str, Any] | None
    current_log: dict[str, float]
    verification: dict[str, Any]
    log_errors: dict[str, float]
    noise: dict[str, float]
    duration_s: float
    #: the faster log a constant needs (:func:`logging_advice`), or None
    logging: dict[str, Any] | None = None

    def to_dict(self) -> dict[str, Any]:
        worst = self.chosen.worst if self.chosen is not None else None
        return {
            "needed": self.needed, "reasons": self.reasons, "coverage": self.coverage,
            "rivals": [{"name": r.name, "items": list(r.items)} for r in self.rivals],
            "candidates": [c.to_dict() for c in self.candidates],
            "chosen": self.chosen.to_dict() if self.chosen is not None else None,
            "separation": _finite(worst), "misclassification": _finite(confusion(worst)) if worst is not None else None,
            "current_log_separation": {k: _finite(v) for k, v in self.current_log.items()},
            "current_log_errors": {k: _finite(v) for k, v in self.log_errors.items()},
            "verification": self.verification, "noise": {k: _finite(v) for k, v in self.noise.items()},
            "duration_s": self.duration_s, "mission": self.mission, "logging": self.logging,
            "message": self.message(),
        }

    def message(self) -> str:
        if not self.needed:
            said = [r for r in self.reasons if not self.logging or r != self.logging["reason"]]
            return "nothing to settle by an excitation: " + ("; ".join(said) or "the diagnosis is not ambiguous and "
                                                             "the log covers reversals, low speed, a range of speeds "
                                                             "and of voltages") + (
                       f"; but this log is too slow to check L: log at {self.logging['rate_hz'] / 1e3:.3g} kHz or "
                       "faster" if self.logging else "")
        if self.chosen is None:
            return "no candidate experiment ran within the limits: " + "; ".join(c.note for c in self.candidates)
        z = self.chosen.worst
        before = min(self.current_log.values()) if self.current_log else math.nan
        each = [f"{e:.3g}" for e in self.log_errors.values()]
        misses = ", ".join(each[:-1]) + " and " + each[-1] if len(each) > 1 else "".join(each)
        fits = f"; their free runs miss it by {misses} noise units" if misses else ""
        if misses and before > z and confusion(before) <= 0.05:  # no run separates them better than the log
            return (f"this log already separates the rivals by z = {before:.3g} noise standard deviations, more "
                    f"than the best experiment the optimiser runs within the limits ('{self.chosen.name}', z = "
                    f"{z:.3g}){fits}: a rival that explains the log misses it by about one; where none does, "
                    "something none of them holds is missing")
        if before > z:  # neither the log nor any run tells them apart
            return (f"no experiment the optimiser runs within the limits separates the rivals better than this log "
                    f"(z = {before:.3g} noise standard deviations{fits}; best run '{self.chosen.name}', z = {z:.3g}): "
                    f"a likelihood-ratio test would confuse them with probability {confusion(before):.2g}; wider "
                    "limits (--voltage, --current) or a longer run (--duration) may")
        return (f"run '{self.chosen.name}' ({self.chosen.description}): the rivals differ by z = {z:.3g} noise "
                f"standard deviations (this log: {before:.3g}{fits}); a likelihood-ratio test would confuse them "
                f"with probability {confusion(z):.2g}")


def _finite(x: float | None) -> float | None:
    return float(x) if x is not None and math.isfinite(x) else None


def _scales(plant: DCMotorPlant, voltage: float, current: float) -> dict[str, float]:
    """Top speed held within the limits [rad/s] and the load torque, thrust there; the constants used by probes."""
    p = plant.params

    def within(w: float) -> bool:  # the plant's effects included (a friction lowers the top speed)
        try:
            x, v = equilibrium(plant, w)
        except ThrustshapeError:
            return False
        return abs(v) <= voltage and abs(float(x[1])) <= current

    hi = 1.0
    while within(hi) and hi < 1e7:  # bracket, then bisect: the fastest steady speed within both limits
        hi *= 2.0
    lo = 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if within(mid) else (lo, mid)
    return {"w_top": lo, "tau_top": p.B * lo + p.c_tau * lo * lo, "F_top": p.c_f * lo * lo, "V": voltage,
            "c_tau": p.c_tau, "c_f": p.c_f, "tau_m": p.J * p.R / (p.k_t * p.k_e),
            # time to the top speed at the current limit (no load): a tight current limit slows every change
            "tau_i": p.J * lo / (p.k_t * current)}


def rivals_from(plant: DCMotorPlant, log: Log, res: DiagnoseResult, opt: DesignOptions,
                scales: dict[str, float], cov: dict[str, Any]) -> tuple[list[Rival], list[str], bool]:
    """The rival explanations (module doc), the reasons an experiment is needed, and whether the rivals are
    probes (the diagnosed plant first: the experiment must *reveal* each probe, not tell probes apart)."""
    from ocp.identify import fit

    def fitted(items: Sequence[str]) -> Rival:
        name = " + ".join(items) or "nothing missing"
        body = fit(plant, log, list(items)).plant if items else res.plant  # refined: see the module doc
        return Rival(name, tuple(items), body)

    if opt.rivals is not None:
        return [fitted(r) for r in opt.rivals], ["rivals given by the user"], False
    # a gain on the command no excitation tells from the constants it scales (.gain): said, not a rival
    reasons = [str(a["reason"]) for a in res.ambiguous if a["alternative"] == COMMON_GAIN]
    pairs, sets = [a for a in res.ambiguous if a["alternative"] != COMMON_GAIN], []
    gaps = open_gaps(cov)
    if pairs:
        sets.append(tuple(sorted(res.verdict)))
        closest = sorted(pairs, key=lambda a: float(a["alternative_score"]))  # best-fitting first
        for k, a in enumerate(closest):
            if len(sets) == MAX_RIVALS:
                reasons.append(f"{len(closest) - k} further ambiguities not taken as rivals (at most {MAX_RIVALS}: "
                               "the alternatives that fit the log best)")
                break
            swapped = tuple(sorted(str(a["alternative"]) if v == a["adopted"] else v for v in res.verdict))
            reasons.append(str(a["reason"]))
            sets += [] if swapped in sets else [swapped]
        reasons += [f"{text} (an effect may hide there)" for _, text, _ in gaps]
        return [fitted(s) for s in sets], reasons, False
    out = [Rival("diagnosed plant", tuple(res.verdict), res.plant)]
    present = {e.name for e in res.plant.effects} | set(res.verdict)
    for _, text, probes in gaps:
        reasons.append(text)
        for name in probes:
            if name in present or any(r.name.startswith(name) for r in out):
                continue
            if name.startswith("param:"):  # (a speed range for B, forward rotation for c_tau and c_f)
                body = with_constant(res.plant, name.removeprefix("param:"), 0.5)
                out.append(Rival(f"{name} (+50 %)", (*res.verdict, name), body))
            else:
                values = PROBES[name](scales)
                out.append(Rival(f"{name} (probe)", (*res.verdict, name), with_effect(res.plant, name, values)))
    return out, reasons, True


def design(plant: DCMotorPlant, log: Log, diagnosis: DiagnoseResult, options: DesignOptions | None = None,
           progress: Callable[[float], None] | None = None) -> DesignResult:
    """Propose the experiment that separates the rival explanations of ``log`` (module doc)."""
    from ocp.optimize.mission import Mission

    opt = options or DesignOptions()
    if not dynamic(log):
        raise LogError("log", "designing an experiment needs a time series with armature voltage, current and "
                              "speed (a sweep or a flight log is checked point by point)")
    voltage = opt.voltage or float(np.max(np.abs(log.voltage)))
    current = opt.current or float(np.max(np.abs(log.current)))
    if voltage <= 0 or current <= 0:
        raise ParameterError("voltage" if voltage <= 0 else "current", "the log has no non-zero peak; give the limit")
    sc = _scales(diagnosis.plant, voltage, current)
    tau = max(sc["tau_m"], sc["tau_i"])  # the time scale of the experiment's changes [s]
    duration = opt.duration_s or float(np.clip(60.0 * tau, 2.0, 20.0))
    cov = coverage(log)
    rivals, reasons, detect = rivals_from(plant, log, diagnosis, opt, sc, cov)
    rivals, left = _simulable(rivals, log, keep_first=detect)
    advice = logging_advice(plant, log)
    reasons += left + ([advice["reason"]] if advice else [])
    noise = noise_levels(log)
    sigma = np.array([noise[ch] for ch in CHANNELS])
    rate = 1.0 / log.dt
    errors = {} if detect else {r.name: _log_error(r.plant, log, noise) for r in rivals}
    base: dict[str, Any] = dict(needed=len(rivals) > 1, reasons=reasons, coverage=cov, rivals=rivals, noise=noise,
                duration_s=duration, log_errors=errors, logging=advice)
    if len(rivals) < 2:
        return DesignResult(**base, candidates=[], chosen=None, mission=None, current_log={}, verification={})
    tl, vl = held_on_grid(log.t, log.voltage, log.dt)
    x0 = (float(log.omega[0]), float(log.current[0]))
    before, _ = pair_separations(rivals, tl, vl, sigma, rate, diagnosis.tolerance, x0, detect)
    params = plant_to_mapping(diagnosis.plant)
    scored: list[tuple[Candidate, dict[str, Any], Any]] = []
    excs = candidates(0.95 * sc["w_top"], duration, tau)
    for k, exc in enumerate(excs):
        scored.append(_score(exc, params, diagnosis.plant.params.c_f, voltage, current, opt, rivals, sigma, rate,
                             log.dt, detect))
        if progress is not None:
            progress(0.1 + 0.6 * (k + 1) / len(excs))
    top = sorted((s for s in scored if s[0].runnable), key=lambda s: -s[0].worst)[:SHORTLIST]
    final = []
    for k, (cand, mission, res) in enumerate(top):
        t, v = held_on_grid(res.arrays["t"], res.arrays["voltage"], log.dt)
        z, rms = pair_separations(rivals, t, v, sigma, rate, diagnosis.tolerance, detect=detect)
        final.append((Candidate(cand.name, cand.description, True, cand.note, cand.raw, z, rms), mission, res))
        if progress is not None:
            progress(0.7 + 0.3 * (k + 1) / max(len(top), 1))
    finals = {c.name: c for c, _, _ in final}
    cands = [finals.get(c.name, c) for c, _, _ in scored]
    if not final:
        return DesignResult(**base, candidates=cands, chosen=None, mission=None, current_log=before, verification={})
    best, mission, res = max(final, key=lambda s: s[0].worst)
    Mission.model_validate(mission)  # what is proposed is a valid mission
    ver = {"source": res.source, "max_abs_current": float(np.max(np.abs(res.arrays["current"]))),
           "max_abs_voltage": float(np.max(np.abs(res.arrays["voltage"]))), "path_ok": res.path_ok,
           "tracking_rms_error": res.verification.get("tracking_rms_error"), "duration_s": float(res.arrays["t"][-1]),
           "limits": {"voltage": voltage, "current": current}}
    return DesignResult(**base, candidates=cands, chosen=best, mission=mission, current_log=before, verification=ver)


def logging_advice(plant: DCMotorPlant, log: Log) -> dict[str, Any] | None:
    """Where ``log`` samples too slowly to check ``L`` (:func:`.regression.slow_armature`, ``plant``'s L/R, as
    :func:`ocp.identify.diagnose` judges it): the constant, the log's rate, the rate from which the check resolves
    it and the advised one [Hz] (:func:`.regression.advised_rate`), and why; else None. Under two samples per L/R
    an inductance error, a current filter and a fraction of a sample of command timing look alike whatever the
    command; logged faster under voltage steps, ``L`` is named (proving-ground rigs: :data:`.regression.
    ADVISED_SAMPLES`)."""
    p = plant.params
    if not slow_armature(p, log.dt):
        return None
    rate = advised_rate(p)
    return {"constant": "L", "log_rate_hz": 1.0 / log.dt, "resolves_from_hz": ARMATURE_SAMPLES * p.R / p.L,
            "rate_hz": rate,
            "reason": f"L cannot be checked at this log's rate ({1.0 / log.dt:.4g} Hz: L/R = {1e3 * p.L / p.R:.3g} "
                      "ms is under two samples): no excitation tells an inductance error from current filtering "
                      f"or sub-sample command timing there; log current and voltage at {rate / 1e3:.3g} kHz or "
                      f"faster ({ADVISED_SAMPLES:g} samples per L/R) under voltage steps to check it"}


def _simulable(rivals: list[Rival], log: Log, keep_first: bool) -> tuple[list[Rival], list[str]]:
    """``rivals`` less those the free run cannot simulate at the log's sample period (over
    :data:`.predict.MAX_STEPS_PER_SAMPLE` RK4 steps a sample at rest, where a proposal starts, or at the log's first
    state), and a reason for each left out. ``keep_first``: the diagnosed plant, which every probe is told from, is
    kept (where it cannot be simulated, the design fails as the free run says). Proving ground: a 3 % brush drop probe
    on a 200 Hz log needed 4,401 steps a sample at rest (its contact's ``tanh(i / i_eps)`` at zero current)."""
    def steps(r: Rival, x: np.ndarray | None) -> int:
        return substeps(r.plant, log.dt, x) // SUBSTEPS

    out, left = [], []
    for k, r in enumerate(rivals):
        states = (None, np.concatenate([[log.omega[0], log.current[0]], np.zeros(len(r.plant.state_names) - 2)]))
        worst = max(steps(r, x) for x in states)
        if worst <= MAX_STEPS_PER_SAMPLE or (keep_first and k == 0):
            out.append(r)
        else:
            left.append(f"{r.name} left out: simulating it at this log's rate takes {worst} RK4 steps a sample "
                        f"(at most {MAX_STEPS_PER_SAMPLE})")
    return out, left


def _log_error(plant: DCMotorPlant, log: Log, noise: dict[str, float]) -> float:
    """How far ``plant``'s free run misses ``log`` [noise units]: the RMS over the channels of
    :func:`ocp.identify.fit.channel_rms` (the log aligned as :func:`ocp.identify.fit` aligns it) over ``noise``."""
    from ocp.identify.fit import FitOptions, channel_rms

    opt = FitOptions()
    rms = channel_rms(plant, aligned(plant, log, opt.max_logging_skew)[1], opt.segment_s)
    return math.sqrt(sum((rms[ch] / noise[ch]) ** 2 for ch in CHANNELS) / len(CHANNELS))


def _score(exc_: Excitation, params: dict[str, Any], c_f: float, voltage: float, current: float, opt: DesignOptions,
           rivals: list[Rival], sigma: np.ndarray, rate: float, dt_log: float,
           detect: bool) -> tuple[Candidate, dict[str, Any], Any]:
    """Optimise one candidate within the limits; its raw separations (no refit) when it runs within them."""
    from ocp.optimize.mission import Mission
    from ocp.optimize.result import Source
    from ocp.optimize.solve import optimize

    mission = mission_for(exc_, params, c_f, voltage, current, opt.time_limit_s)
    try:
        res = optimize(Mission.model_validate(mission))
    except ThrustshapeError as exc:  # nothing within the limits (the fallback too): this candidate cannot run
        return Candidate(exc_.name, exc_.description, False, f"not run: {exc.field}: {exc.reason}"), mission, None
    i_max, v_max = float(np.max(np.abs(res.arrays["current"]))), float(np.max(np.abs(res.arrays["voltage"])))
    ok = res.source is Source.OPTIMIZED and i_max <= current * (1 + 1e-6) and v_max <= voltage * (1 + 1e-6)
    note = (f"optimised within the limits (peak {i_max:.3g} A, {v_max:.3g} V)" if ok else
            f"not run: {res.source} ({res.reason or 'limits exceeded'}; peak {i_max:.3g} A, {v_max:.3g} V)")
    if not ok:
        return Candidate(exc_.name, exc_.description, False, note), mission, res
    t, v = held_on_grid(res.arrays["t"], res.arrays["voltage"], dt_log)
    raw, rms = pair_separations(rivals, t, v, sigma, rate, None, detect=detect)
    return Candidate(exc_.name, exc_.description, True, note, raw, {}, rms), mission, res
