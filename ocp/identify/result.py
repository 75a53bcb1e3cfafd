"""What :func:`.diagnose.diagnose` takes and gives: its options, and its result (the verdict, the rounds' rankings,
the calibrated plant) with the JSON form the CLI, the service and the page read."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from pydantic import BaseModel, ConfigDict, Field

from ocp.identify.align import Alignment
from ocp.identify.explain import message
from ocp.identify.predict import CHANNEL_UNITS
from ocp.model.plant import DCMotorPlant


class DiagnoseOptions(BaseModel):
    """Knobs of :func:`.diagnose.diagnose` (defaults suit 1 kHz logs of a few seconds)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    segment_s: float = Field(default=0.5, gt=0)
    holdout_every: int = Field(default=3, ge=2)
    cross_validate: bool = True  # models scored by cross-validation (each segment class held out in turn,
    # :mod:`.diagnose`'s item 2)
    min_improvement: float = Field(default=0.12, gt=0, lt=1)  # an effect's held-out score must fall by this
    # [noise units] a model with every equation within this of its noise level (1) is done (session 10: not 1.15); a
    # constant is named only for an equation above it, an effect's material fall may show a noise level overestimated
    noise_floor: float = Field(default=1.0, gt=0)
    max_effects: int = Field(default=3, ge=1, le=10)  # at most this many items in the verdict
    include_params: bool = True  # constants may be named beyond the tolerance (else: calibration only)
    candidates: tuple[str, ...] | None = None  # None: the whole catalogue (+ corrections)
    tolerance: float = Field(default=0.10, gt=0, lt=1)  # a constant is named wrong only beyond this (relative)
    ambiguity_margin: float = Field(default=0.02, ge=0, lt=0.5)  # equal held-out fits within this -> ambiguous
    max_logging_skew: float = Field(default=2.0, ge=0, le=20)  # [samples] lags logging conventions explain


def finite(x: float) -> float | None:
    """JSON-safe float (None for NaN/inf)."""
    return float(x) if math.isfinite(x) else None


@dataclass(frozen=True)
class Score:
    """Held-out free-run error of one plant: per channel RMS [channel unit], the combined E [-], and the current
    sensor's lag [samples] the current was read through (:func:`.predict.read_current`)."""

    rms: dict[str, float]
    combined: float
    current_lag: float = 0.0


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
                "heldout_rms": {k: finite(v) for k, v in self.heldout_rms.items()}, "explanation": self.explanation}


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
    alignment: Alignment | None = None
    calibration: dict[str, dict[str, Any]] = field(default_factory=dict)
    ambiguous: list[dict[str, Any]] = field(default_factory=list)
    angle_periodic: dict[str, Any] | None = None
    tolerance: float = 0.10
    blind_spots: list[dict[str, Any]] = field(default_factory=list)  # what the log cannot show (.coverage)
    evidence: dict[str, dict[str, Any]] = field(default_factory=dict)  # how each name won (.strength)

    @property
    def ranking(self) -> list[RankEntry]:
        """First-round ranking (every candidate against the given model)."""
        return self.rounds[0].entries if self.rounds else []

    def to_dict(self) -> dict[str, Any]:
        return {
            "verdict": self.verdict,
            "ranking": [e.to_dict() for e in self.ranking],
            "explanations": self.explanations,
            "message": message(self.verdict, self.explanations, self.ambiguous, self.evidence),
            "alignment": self.alignment.to_dict() if self.alignment else None,
            "calibration": {k: {kk: finite(vv) if isinstance(vv, float) else vv for kk, vv in v.items()}
                            for k, v in self.calibration.items()},
            "tolerance": self.tolerance, "blind_spots": self.blind_spots, "evidence": self.evidence,
            "ambiguous": [{k: finite(v) if isinstance(v, float) else v for k, v in a.items()} for a in self.ambiguous],
            "angle_periodic": self.angle_periodic, "noise": {k: finite(v) for k, v in self.noise.items()},
            "units": CHANNEL_UNITS,
            "rounds": [{"baseline_rms": {k: finite(v) for k, v in r.baseline.rms.items()},
                        "baseline_score": finite(r.baseline.combined),
                        "current_sensor_lag": r.baseline.current_lag,
                        "ranking": [e.to_dict() for e in r.entries]} for r in self.rounds],
        }
