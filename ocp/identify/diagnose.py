"""diagnose: which physics is missing? Fit every candidate, rank by HELD-OUT error reduction.

Procedure (greedy forward selection):

1. Split the log into segments of ``segment_s`` seconds; every third segment is held out
   (``holdout_every``), the rest trains. Steady-state sweeps: every third row is held out.
2. Score a plant by its held-out free-run error: per channel (speed, current, thrust) the RMS
   divided by the sensor-noise level (:func:`ocp.identify.predict.noise_levels`), combined as
   ``E = sqrt(mean_channel (rms/noise)^2)``. A perfect model of a clean rig scores about 1.
3. For each candidate (catalogue effect or nominal-constant correction): fit its parameters, jointly
   with those already selected, by equation error on the training data; score on held-out data.
   ``improvement = 1 - E_candidate / E_current``.
4. Significance rule: the best candidate is accepted when its improvement is at least
   ``min_improvement`` AND the current model is not yet at the noise floor (``E > noise_floor``).
   On clean data nothing passes: the verdict is empty ("nothing missing").
5. Repeat with the accepted candidate in the model (up to ``max_effects``), so several hidden
   effects are found one after the other.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ocp.identify.candidates import Candidate, all_candidates, candidate
from ocp.identify.equations import allowed
from ocp.identify.estimate import Estimate, equation_error_fit, equation_scales, free_run
from ocp.identify.predict import CHANNEL_UNITS, CHANNELS, noise_levels
from ocp.logs import Log, LogKind
from ocp.plant import DCMotorPlant


class DiagnoseOptions(BaseModel):
    """Knobs of :func:`diagnose` (defaults suit 1 kHz logs of a few seconds)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    segment_s: float = Field(default=0.5, gt=0)
    holdout_every: int = Field(default=3, ge=2)
    min_improvement: float = Field(default=0.10, gt=0, lt=1)
    noise_floor: float = Field(default=1.5, gt=0)
    max_effects: int = Field(default=3, ge=1, le=10)
    include_params: bool = True
    candidates: tuple[str, ...] | None = None  # None: the whole catalogue (+ corrections)


def dynamic(log: Log) -> bool:
    """Whether the dynamic check (free run under the armature voltage) applies: a complete time series."""
    return log.complete and log.kind is LogKind.TIME_SERIES


def finite(x: float) -> float | None:
    """JSON-safe float (None for NaN/inf)."""
    return float(x) if math.isfinite(x) else None


@dataclass(frozen=True)
class Split:
    """Training and held-out masks (N,) over log samples."""

    train: np.ndarray
    test: np.ndarray


def split(log: Log, segment_s: float, every: int) -> Split:
    """Every ``every``-th segment (row for sweeps) held out."""
    if log.kind is LogKind.STEADY_STATE:
        test = np.arange(log.n) % every == every - 1
        return Split(~test, test)
    length = max(2, round(segment_s / log.dt))
    test = (np.arange(log.n) // length) % every == every - 1
    return Split(~test, test)


@dataclass(frozen=True)
class Score:
    """Held-out free-run error of one plant: per channel RMS [channel unit] and the combined E [-]."""

    rms: dict[str, float]
    combined: float


def score(plant: DCMotorPlant, log: Log, mask: np.ndarray, noise: dict[str, float], segment_s: float) -> Score:
    fr = free_run(plant, log, segment_s)
    keep = mask[fr.idx]
    rms = {ch: float(np.sqrt(np.mean((getattr(log, ch)[fr.idx][keep] - fr.channel(ch)[keep]) ** 2)))
           for ch in CHANNELS}
    comb = math.sqrt(sum((rms[ch] / noise[ch]) ** 2 for ch in CHANNELS) / len(CHANNELS))
    return Score(rms, comb if math.isfinite(comb) else math.inf)


@dataclass(frozen=True)
class RankEntry:
    """One candidate in one round."""

    name: str
    improvement: float
    significant: bool
    parameters: dict[str, float]
    units: dict[str, str]
    heldout_rms: dict[str, float]
    explanation: str

    def to_dict(self) -> dict[str, Any]:
        return {"effect": self.name, "improvement": finite(self.improvement), "significant": self.significant,
                "parameters": {k: finite(v) for k, v in self.parameters.items()}, "units": self.units,
                "heldout_rms": {k: finite(v) for k, v in self.heldout_rms.items()},
                "explanation": self.explanation}


@dataclass(frozen=True)
class Round:
    baseline: Score
    entries: list[RankEntry]


@dataclass(frozen=True)
class DiagnoseResult:
    """Verdict (names, most important first; empty when nothing is missing), rounds, final plant."""

    verdict: list[str]
    rounds: list[Round]
    plant: DCMotorPlant
    noise: dict[str, float]
    explanations: list[str] = field(default_factory=list)

    @property
    def ranking(self) -> list[RankEntry]:
        """First-round ranking (every candidate against the given model)."""
        return self.rounds[0].entries if self.rounds else []

    def to_dict(self) -> dict[str, Any]:
        return {
            "verdict": self.verdict,
            "ranking": [e.to_dict() for e in self.ranking],
            "explanations": self.explanations,
            "message": "nothing missing" if not self.verdict else "; ".join(self.explanations),
            "noise": {k: finite(v) for k, v in self.noise.items()},
            "units": CHANNEL_UNITS,
            "rounds": [{"baseline_rms": {k: finite(v) for k, v in r.baseline.rms.items()},
                        "baseline_score": finite(r.baseline.combined),
                        "ranking": [e.to_dict() for e in r.entries]} for r in self.rounds],
        }


def _try(base: DCMotorPlant, cand: Candidate, log: Log, sp: Split, scales: dict[str, float]) -> Estimate:
    """Fit one candidate on top of ``base`` (those already chosen stay at their values)."""
    return equation_error_fit(base, [cand], log, sp.train, scales)


def diagnose(plant: DCMotorPlant, log: Log, options: DiagnoseOptions | None = None) -> DiagnoseResult:
    """Rank candidate effects by held-out error reduction and say which are missing (module doc)."""
    opt = options or DiagnoseOptions()
    # --- issue #13 hook: sweeps, ESC rigs and flight logs are checked point by point (no time effect) ---
    if not dynamic(log):
        from ocp.identify.steady import diagnose_points

        return diagnose_points(plant, log, opt)
    # --- end of hook ---
    pool = ([candidate(n) for n in opt.candidates] if opt.candidates is not None
            else all_candidates(opt.include_params))
    present = {e.name for e in plant.effects}
    pool = [c for c in pool if c.name not in present and allowed(c.name, c.channel, log)]  # issue #13 filter
    noise = noise_levels(log)
    sp = split(log, opt.segment_s, opt.holdout_every)
    current, chosen, verdict, explanations, rounds = plant, [], [], [], []
    for _ in range(opt.max_effects):
        base_score = score(current, log, sp.test, noise, opt.segment_s)
        scales = equation_scales(current, log, sp.train)
        entries: list[tuple[RankEntry, DCMotorPlant, Candidate]] = []
        for cand in pool:
            if cand in chosen:
                continue
            est = _try(current, cand, log, sp, scales)
            s = score(est.plant, log, sp.test, noise, opt.segment_s)
            imp = 1.0 - s.combined / base_score.combined if math.isfinite(s.combined) else -math.inf
            ok = imp >= opt.min_improvement and base_score.combined > opt.noise_floor
            entry = RankEntry(cand.name, imp, ok, cand.values(est.plant), cand.units(), s.rms,
                              cand.explain(current, est.plant))
            entries.append((entry, est.plant, cand))
        entries.sort(key=lambda e: (-e[0].improvement, len(e[2].keys)))
        rounds.append(Round(base_score, [e[0] for e in entries]))
        if not entries or not entries[0][0].significant:
            break
        best, current, cand = entries[0]
        chosen.append(cand)
        if len(chosen) > 1:  # joint refit of everything chosen so far, from the values found
            current = equation_error_fit(current, chosen, log, sp.train, scales).plant
        verdict.append(best.name)
        explanations.append(f"{best.explanation} Held-out error down {100 * best.improvement:.0f} %.")
    return DiagnoseResult(verdict, rounds, current, noise, explanations)
