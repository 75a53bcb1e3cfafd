"""fit: add named effects (and constant corrections), refit, report before/after, write a calibrated file.

Two stages: an equation-error fit (one-step residuals; fast, linear in most effect amplitudes)
gives the start; a free-run refinement (plant simulated under the measured voltage, restarted
every ``segment_s``) polishes it and is kept only if it lowers the free-run error. The fit is adopted only where
it predicts the log's free run better than the plant it started from (:func:`adoption_note`); else the calibrated
plant is the starting one, and the result says so beside the fitted values and the error they gave. Before/after
RMS per channel (free run) and per equation (one step) are reported on the whole log, with the
parameters' standard errors and correlations from the last stage's Jacobian. Both stages see the log realigned by
the command-to-sensor lag logging conventions explain, reported as ``alignment``
(:func:`ocp.identify.diagnose.aligned`, as ``check`` and ``diagnose`` do): unaligned, the armature's constants
would be fitted to a logging convention. An angle ripple added to a plant without one takes the count ``diagnose``
finds (:func:`with_ripple_count`); the free runs read the rotor angle from the log (:mod:`.predict`).

The calibrated file is the parameter-file format of :mod:`ocp.model.effects` (``MotorParams`` keys +
``effects``), readable by :func:`ocp.model.effects.load_plant` and, for the constants, by
:func:`ocp.model.params.load_params` (it ignores the ``effects`` block).
"""

from __future__ import annotations

import json
import math
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ocp.identify.align import Alignment
from ocp.identify.candidates import candidate
from ocp.identify.clipping import clipped, widened
from ocp.identify.diagnose import aligned, diagnose, dynamic
from ocp.identify.drops import DEAD_BAND_FORMS
from ocp.identify.estimate import equation_error_fit, equation_scales, free_run_errors, free_run_fit
from ocp.identify.holdout import CLIP_MARGIN
from ocp.identify.predict import (
    CHANNEL_UNITS,
    CHANNELS,
    EQUATION_UNITS,
    EQUATIONS,
    free_run,
    noise_levels,
    one_step,
    read_current,
)
from ocp.identify.result import finite
from ocp.logs import Log
from ocp.model.effects import Cogging, VoltageDeadband, plant_to_mapping
from ocp.model.plant import DCMotorPlant
from ocp.parallel import own_threads


class FitOptions(BaseModel):
    """Knobs of :func:`fit`."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    segment_s: float = Field(default=0.5, gt=0)
    refine: bool = True  # free-run refinement after the equation-error start
    max_nfev: int = Field(default=30, ge=1, le=1000)
    max_logging_skew: float = Field(default=2.0, ge=0, le=20)  # [samples] lags logging conventions explain


def channel_rms(plant: DCMotorPlant, log: Log, segment_s: float) -> dict[str, float]:
    """Free-run RMS error per channel [rad/s, A, N] over the whole log (the current read through the current
    sensor's lag that matches it best, :func:`.predict.read_current`)."""
    return _read_rms(plant, log, segment_s)[0]


def _read_rms(plant: DCMotorPlant, log: Log, segment_s: float) -> tuple[dict[str, float], float]:
    """:func:`channel_rms` and the current sensor's lag [samples] the current was read through."""
    fr = read_current(free_run(plant, log, segment_s), log)
    rms = {ch: float(np.sqrt(np.mean((getattr(log, ch)[fr.idx] - fr.channel(ch)) ** 2))) for ch in CHANNELS}
    return rms, fr.current_lag


def equation_rms(plant: DCMotorPlant, log: Log) -> dict[str, float]:
    """One-step residual RMS per equation [N m, V, N]."""
    r = one_step(plant, log)
    return {eq: float(np.sqrt(np.mean(r.equation(eq) ** 2))) for eq in EQUATIONS}


@dataclass(frozen=True)
class FitResult:
    """Before/after errors, fitted parameters with uncertainties, and the calibrated plant."""

    plant: DCMotorPlant
    effects: tuple[str, ...]
    stage: str  # "equation-error" or "free-run": which stage's values were kept
    names: tuple[str, ...]
    values: np.ndarray
    stderr: np.ndarray
    correlation: np.ndarray
    before: dict[str, float]
    after: dict[str, float]
    before_equations: dict[str, float]
    after_equations: dict[str, float]
    alignment: Alignment | None = None  # time series only (a sweep's rows have no command timing)
    current_sensor_lag: tuple[float, float] = (0.0, 0.0)  # [samples] before, after: :func:`channel_rms`'s read
    #: False: the fitted plant predicted the free run worse than the starting one; :attr:`plant` is the starting
    #: plant, ``values`` and ``after`` the fit's (why in ``note``)
    adopted: bool = True
    note: str | None = None

    def calibrated(self, name: str | None = None) -> dict[str, Any]:
        """The calibrated parameter file as a mapping (JSON-ready)."""
        notes: dict[str, Any] = {
            "fitted_by": "thrustshape fit", "effects_added": list(self.effects), "stage": self.stage,
            "free_run_rms_before": {k: finite(v) for k, v in self.before.items()},
            "free_run_rms_after": {k: finite(v) for k, v in self.after.items()}}
        if not self.adopted:
            notes |= {"adopted": False, "note": self.note}
        return plant_to_mapping(self.plant, name=name, notes=notes)

    def write(self, path: str | Path, name: str | None = None) -> None:
        """Write the calibrated parameter file (JSON)."""
        Path(path).write_text(json.dumps(self.calibrated(name), indent=2, allow_nan=False) + "\n", encoding="utf-8")

    def to_dict(self) -> dict[str, Any]:
        return {
            "effects": list(self.effects),
            "stage": self.stage,
            "adopted": self.adopted,
            "note": self.note,
            "alignment": self.alignment.to_dict() if self.alignment else None,
            "parameters": {n: {"value": finite(v), "stderr": finite(s)}
                           for n, v, s in zip(self.names, self.values, self.stderr, strict=True)},
            "correlation": {"names": list(self.names),
                            "matrix": [[finite(float(c)) for c in row] for row in self.correlation]},
            "rms_before": {k: finite(v) for k, v in self.before.items()},
            "rms_after": {k: finite(v) for k, v in self.after.items()},
            "current_sensor_lag": dict(zip(("before", "after"), self.current_sensor_lag, strict=True)),
            "equation_rms_before": {k: finite(v) for k, v in self.before_equations.items()},
            "equation_rms_after": {k: finite(v) for k, v in self.after_equations.items()},
            "units": {**CHANNEL_UNITS, **{f"equation.{k}": v for k, v in EQUATION_UNITS.items()}},
            "calibrated": self.calibrated(),
        }


def _combined(errors: np.ndarray) -> float:
    return float(np.sqrt(np.mean(errors**2))) if errors.size else math.inf


def with_ripple_count(plant: DCMotorPlant, log: Log, effects: Sequence[str]) -> DCMotorPlant:
    """``plant`` with an angle ripple at the count ``diagnose`` finds in ``log`` (its ``angle_periodic``), where
    ``effects`` adds a ripple the plant has none of; else ``plant``. Without, the catalogue's default count (2/rev)
    was fitted to a ripple of any count. A ripple the plant has keeps its count (a parameter file or a diagnosis
    gave it)."""
    if "cogging" not in effects or any(isinstance(e, Cogging) for e in plant.effects):
        return plant
    found = diagnose(plant, log).angle_periodic
    n = int(found["periods"]) if found else 0
    return replace(plant, effects=(*plant.effects, Cogging(periods=float(n)))) if n > 0 else plant


#: a dead band added by ``fit`` starts at the best of these shares of the log's peak command, in either form, by the
#: free run (:func:`dead_band_start`)
DEAD_BAND_STARTS = tuple(float(x) for x in np.geomspace(0.01, 0.3, 10))


def dead_band_start(plant: DCMotorPlant, log: Log, effects: Sequence[str], rows: np.ndarray, noise: dict[str, float],
                    segment_s: float) -> DCMotorPlant:
    """``plant`` with the dead band ``effects`` add (where it has none) at the form (:data:`.drops.DEAD_BAND_FORMS`:
    shifted, a gap; a fixed shape the fit keeps) and width (:data:`DEAD_BAND_STARTS`) whose free run predicts ``log``
    best on ``rows`` ((N,) bool); else ``plant``. From the catalogue's guess (0.1 V, a small drive's) in the shifted
    form, a 3.8 V gap was fitted at 0.003 V: a gap's residual moves only with the commands near its edge, and the
    one-step torque equation (a fast armature's current follows the command within the step) fitted it worse than
    none though its free run fell from 8.1 to 3.0 noise units (``tests/identify/test_dead_band_gap.py``): the
    free-run refinement starts from this width too. A dead band the plant has keeps its form and width (a parameter
    file or a diagnosis gave it)."""
    if "voltage_deadband" not in effects or any(isinstance(e, VoltageDeadband) for e in plant.effects):
        return plant
    peak = float(np.max(np.abs(log.voltage)))
    trials = [replace(plant, effects=(*plant.effects, VoltageDeadband(v_db=x * peak, gap=g)))
              for g in DEAD_BAND_FORMS for x in DEAD_BAND_STARTS]
    return min(trials, key=lambda q: _combined(free_run_errors(q, log, rows, noise, segment_s)))


@own_threads
def fit(plant: DCMotorPlant, log: Log, effects: Sequence[str], options: FitOptions | None = None) -> FitResult:
    """Add ``effects`` (catalogue names or ``"param:<key>"``) to ``plant`` and fit them to ``log``. The alignment's
    lags run in threads, BLAS in one (:func:`ocp.parallel.own_threads`)."""
    opt = options or FitOptions()
    if not dynamic(log):  # issue #13 hook: sweeps, ESC rigs, flight logs are fitted point by point
        from ocp.identify.steady import fit_points

        return fit_points(plant, log, effects)
    start = plant
    plant = with_ripple_count(plant, log, effects)
    align, log = aligned(plant, log, opt.max_logging_skew)
    cands = [candidate(n) for n in dict.fromkeys(effects)]
    every = ~widened(clipped(log.current), CLIP_MARGIN)  # (a clipped current's rows: :mod:`.holdout`)
    scales = equation_scales(plant, log, every)
    noise = noise_levels(log)
    db = dead_band_start(plant, log, effects, every, noise, opt.segment_s)
    first = [np.array(list(c.values(db).values())) for c in cands]  # the refinement starts there too (its doc)
    also = [np.concatenate(first)] if db is not plant and all(v.size for v in first) else []
    plant = db
    est = equation_error_fit(plant, cands, log, every, scales)
    stage = "equation-error"
    e_est = _combined(free_run_errors(est.plant, log, every, noise, opt.segment_s))
    if opt.refine and cands:
        refined = free_run_fit(est, cands, plant, log, every, noise, opt.segment_s, opt.max_nfev, also)
        e_ref = _combined(free_run_errors(refined.plant, log, every, noise, opt.segment_s))
        if e_ref < e_est:
            est, stage, e_est = refined, "free-run", e_ref
    e_start = _combined(free_run_errors(start, log, every, noise, opt.segment_s))
    note = adoption_note(e_start, e_est)
    (before, lag_before), (after, lag_after) = (_read_rms(p, log, opt.segment_s) for p in (start, est.plant))
    return FitResult(
        plant=est.plant if note is None else start, effects=tuple(c.name for c in cands), stage=stage,
        names=est.names, values=est.values, stderr=est.stderr, correlation=est.correlation, before=before,
        after=after, before_equations=equation_rms(start, log), after_equations=equation_rms(est.plant, log),
        alignment=align, current_sensor_lag=(lag_before, lag_after), adopted=note is None, note=note,
    )


def adoption_note(e_start: float, e_fit: float, what: str = "predicts this log's free run",
                  unit: str = "noise levels") -> str | None:
    """None where the fitted plant's error over the log (``e_fit``: the free run's, combined over the channels in
    noise units; a sweep's equations, :func:`.steady.fit_points`) is below the starting plant's (``e_start``); else
    why the fit is not adopted. Fitted to this very log, added parameters can only lower the error at the optimum:
    a rise means the fit did not reach it (an effect the log cannot show, a ripple's count beyond its sampling) and
    the starting plant is the better one; no fall, that the log holds nothing of them."""
    if e_fit < e_start:
        return None
    return (f"not adopted: the fitted plant {what} no better than the starting plant (combined error "
            f"{e_start:.4g} -> {e_fit:.4g} {unit}); the calibrated plant is the starting one")
