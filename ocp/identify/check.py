"""check: confront a plant with a log and show WHERE it fails.

Two kinds of error, always labelled:

* ``free_run`` -- the plant simulated under the measured voltage (restarted from the measured state
  every ``segment_s``), compared with the measured speed [rad/s], current [A] (read through the current sensor's
  first-order lag that matches the log best, reported: :func:`ocp.identify.predict.read_current`), thrust [N];
* ``one_step`` -- the equation residuals after one sample from the measured state: torque [N m]
  (eq. dc_mechanical), voltage [V] (eq. dc_electrical), thrust [N] (eq. thrust_model).

Both on the log realigned first by the command-to-sensor lag that logging conventions explain (up to
``max_logging_skew`` + 0.75 samples; :func:`ocp.identify.diagnose.aligned`), which is reported: a loop that logs the
command it is about to write beside the sensors it just read is no failure of the model (session 21: unaligned, the
exact plant's free run on the 30 clean proving-ground logs of seeds 0..199 was a median 8.5 noise units off, aligned
2.0).

Breakdowns (mean and RMS of the one-step residuals, RMS of the free-run error, sample count per bin):
thrust direction, near reversals (within ``reversal_window_s`` of a speed sign change) vs away,
speed band (fractions of the peak speed), accelerating vs decelerating (``w w' > 0``), rotor angle
(``bins_angle`` bins of ``theta mod 2 pi``). Whiteness: autocorrelation of each residual and its
cross-correlation with the voltage and the speed, lags 0..``max_lag``, with the 95 % band
``+-1.96/sqrt(N)`` of a white residual.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from pydantic import BaseModel, ConfigDict, Field

from ocp.identify.align import Alignment
from ocp.identify.angle import rotor_angle
from ocp.identify.diagnose import aligned, dynamic
from ocp.identify.predict import (
    CHANNEL_UNITS,
    CHANNELS,
    EQUATION_UNITS,
    EQUATIONS,
    FreeRun,
    Residuals,
    free_run,
    noise_levels,
    one_step,
    read_current,
)
from ocp.identify.result import finite
from ocp.identify.steady import PointCheck, check_points
from ocp.logs import Log, LogKind
from ocp.model.plant import DCMotorPlant
from ocp.parallel import own_threads

SPEED_BANDS = (0.0, 0.1, 0.4, 0.7, 1.0001)


class CheckOptions(BaseModel):
    model_config = ConfigDict(extra="forbid", frozen=True)

    segment_s: float = Field(default=0.5, gt=0)
    reversal_window_s: float = Field(default=0.05, gt=0)
    bins_angle: int = Field(default=12, ge=2, le=360)
    max_lag: int = Field(default=50, ge=1, le=5000)
    max_logging_skew: float = Field(default=2.0, ge=0, le=20)  # [samples] lags logging conventions explain


def _xcorr(a: np.ndarray, b: np.ndarray, max_lag: int) -> np.ndarray:
    """Normalised cross-correlation ``corr(a[k], b[k - lag])`` for lags 0..max_lag, shape (max_lag+1,)."""
    a = (a - a.mean()) / (a.std() or 1.0)
    b = (b - b.mean()) / (b.std() or 1.0)
    n = a.size
    return np.array([float(np.einsum("i,i", a[lag:], b[:n - lag])) / n for lag in range(min(max_lag, n - 1) + 1)])


def groups(log: Log, opt: CheckOptions) -> dict[str, dict[str, np.ndarray]]:
    """Boolean masks (N,) per group and bin label."""
    w = log.omega
    out: dict[str, dict[str, np.ndarray]] = {
        "direction": {"thrust >= 0": log.thrust >= 0, "thrust < 0": log.thrust < 0}}
    peak = float(np.max(np.abs(w))) or 1.0
    out["speed band"] = {f"{int(100 * lo)}-{min(int(100 * hi), 100)} % of peak": (np.abs(w) >= lo * peak)
                         & (np.abs(w) < hi * peak) for lo, hi in itertools.pairwise(SPEED_BANDS)}
    if log.kind is LogKind.STEADY_STATE:
        return out
    cross = np.flatnonzero(np.sign(w[1:]) * np.sign(w[:-1]) < 0)
    near = np.zeros(log.n, dtype=bool)
    for c in log.t[cross]:
        near |= np.abs(log.t - c) <= opt.reversal_window_s
    out["reversal"] = {"near reversal": near, "away": ~near}
    acc = np.gradient(w, log.t)
    out["acceleration"] = {"accelerating": w * acc > 0, "decelerating": w * acc <= 0}
    theta = rotor_angle(log)
    b = np.floor(np.mod(theta, 2 * math.pi) / (2 * math.pi) * opt.bins_angle).astype(int)
    step = 360 // opt.bins_angle
    out["rotor angle"] = {f"{k * step}-{(k + 1) * step} deg": b == k for k in range(opt.bins_angle)}
    return out


@dataclass(frozen=True)
class CheckResult:
    """Where the model fails: overall errors, breakdowns, residual correlations (see module doc)."""

    free_run_rms: dict[str, float]
    free_run_max: dict[str, float]
    one_step_rms: dict[str, float]
    one_step_mean: dict[str, float]
    noise: dict[str, float]
    breakdown: dict[str, dict[str, dict[str, Any]]]
    correlation: dict[str, Any]
    kind: str
    segment_s: float
    free: FreeRun
    residuals: Residuals
    alignment: Alignment

    def to_dict(self) -> dict[str, Any]:
        fd = {k: finite(v) for k, v in self.free_run_rms.items()}
        return {
            "kind": self.kind,
            "alignment": self.alignment.to_dict(),
            "free_run": {"label": f"plant simulated under the measured voltage, restarted every {self.segment_s} s",
                         "current_sensor_lag": self.free.current_lag,
                         "rms": fd, "max": {k: finite(v) for k, v in self.free_run_max.items()},
                         "units": CHANNEL_UNITS},
            "one_step": {"label": "equation residuals after one sample from the measured state",
                         "rms": {k: finite(v) for k, v in self.one_step_rms.items()},
                         "mean": {k: finite(v) for k, v in self.one_step_mean.items()}, "units": EQUATION_UNITS},
            "noise": {k: finite(v) for k, v in self.noise.items()},
            "breakdown": self.breakdown,
            "correlation": self.correlation,
        }


def _bin_stats(mask_r: np.ndarray, mask_f: np.ndarray, res: Residuals, log: Log, fr: FreeRun) -> dict[str, Any]:
    out: dict[str, Any] = {"n": int(mask_r.sum())}
    for eq in EQUATIONS:
        r = res.equation(eq)[mask_r]
        out[f"one_step_mean.{eq}"] = finite(float(r.mean())) if r.size else None
        out[f"one_step_rms.{eq}"] = finite(float(np.sqrt(np.mean(r**2)))) if r.size else None
    for ch in CHANNELS:
        e = (getattr(log, ch)[fr.idx] - fr.channel(ch))[mask_f]
        out[f"free_run_rms.{ch}"] = finite(float(np.sqrt(np.mean(e**2)))) if e.size else None
    return out


def _correlations(res: Residuals, log: Log, max_lag: int) -> dict[str, Any]:
    n = res.idx.size
    band = 1.96 / math.sqrt(n)
    out: dict[str, Any] = {"lags": list(range(max_lag + 1)), "band": band, "acf": {}, "xcorr_voltage": {},
                           "xcorr_omega": {}, "fraction_outside_band": {}}
    for eq in EQUATIONS:
        r = res.equation(eq)
        acf = _xcorr(r, r, max_lag)
        out["acf"][eq] = [finite(float(v)) for v in acf]
        out["xcorr_voltage"][eq] = [finite(float(v)) for v in _xcorr(r, log.voltage[res.idx], max_lag)]
        out["xcorr_omega"][eq] = [finite(float(v)) for v in _xcorr(r, log.omega[res.idx], max_lag)]
        out["fraction_outside_band"][eq] = float(np.mean(np.abs(acf[1:]) > band)) if acf.size > 1 else 0.0
    return out


@own_threads
def check(plant: DCMotorPlant, log: Log, options: CheckOptions | None = None) -> CheckResult | PointCheck:
    """Free-run and one-step errors of ``plant`` on ``log`` (realigned first, module doc), broken down by operating
    condition. The alignment's lags run in threads, BLAS in one (:func:`ocp.parallel.own_threads`)."""
    opt = options or CheckOptions()
    if not dynamic(log):  # issue #13 hook: sweeps, ESC rigs, flight logs: equation by equation, point by point
        return check_points(plant, log)
    align, log = aligned(plant, log, opt.max_logging_skew)
    fr = read_current(free_run(plant, log, opt.segment_s), log)
    res = one_step(plant, log)
    err = {ch: getattr(log, ch)[fr.idx] - fr.channel(ch) for ch in CHANNELS}
    breakdown = {
        g: {label: _bin_stats(m[res.idx], m[fr.idx], res, log, fr) for label, m in bins.items()}
        for g, bins in groups(log, opt).items()
    }
    return CheckResult(
        free_run_rms={ch: float(np.sqrt(np.mean(e**2))) for ch, e in err.items()},
        free_run_max={ch: float(np.max(np.abs(e))) for ch, e in err.items()},
        one_step_rms={eq: float(np.sqrt(np.mean(res.equation(eq) ** 2))) for eq in EQUATIONS},
        one_step_mean={eq: float(np.mean(res.equation(eq))) for eq in EQUATIONS},
        noise=noise_levels(log), breakdown=breakdown,
        correlation=_correlations(res, log, min(opt.max_lag, res.idx.size - 2)),
        kind=log.kind.value, segment_s=opt.segment_s, free=fr, residuals=res, alignment=align,
    )
