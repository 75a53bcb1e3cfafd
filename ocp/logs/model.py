"""The :class:`Log` (one SI table), its units and the options of every reader.

Array layout: every channel shape (N,), SI. ``voltage``, ``current`` and ``thrust`` that the file
does not have are NaN-filled (so the dynamic check's typed arrays stay arrays) and named in
:attr:`Log.absent`; ask :attr:`Log.measured` / :attr:`Log.complete` before using them. ``torque``
and ``command`` are ``None`` when absent. ``voltage`` and ``current`` are the armature's
(``electrical="armature"``) or the supply's (``"supply"``: ESC rigs, flight logs), which decides
the equations they can check (:mod:`ocp.identify.equations`). Problems raise
:class:`~ocp.errors.LogError` naming the column: missing column, NaN/inf, non-monotonic time, too
few samples.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from enum import StrEnum
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, field_validator

from ocp.errors import LogError

G0 = 9.80665  # standard gravity [m/s^2]: kgf -> N
LBF = 4.4482216152605  # [N]
RPM = 2 * math.pi / 60  # [rad/s per rev/min]

#: quantity -> unit name -> factor to SI (value_SI = factor * value); "erpm" is divided by the pole pairs too
UNITS: dict[str, dict[str, float]] = {
    "t": {"s": 1.0, "ms": 1e-3, "us": 1e-6},
    "voltage": {"V": 1.0, "mV": 1e-3},
    "current": {"A": 1.0, "mA": 1e-3},
    "omega": {"rad/s": 1.0, "rpm": RPM, "RPM": RPM, "erpm": RPM, "rev/s": 2 * math.pi, "Hz": 2 * math.pi,
              "deg/s": math.pi / 180},
    "theta": {"rad": 1.0, "deg": math.pi / 180, "rev": 2 * math.pi},
    "thrust": {"N": 1.0, "mN": 1e-3, "kgf": G0, "gf": G0 * 1e-3, "lbf": LBF, "ozf": LBF / 16},
    "torque": {"N m": 1.0, "mN m": 1e-3, "kgf cm": G0 * 1e-2, "ozf in": LBF / 16 * 0.0254},
    "command": {"us": 1.0, "%": 1.0, "fraction": 1.0},
}
QUANTITIES: tuple[str, ...] = tuple(UNITS)
MIN_SAMPLES = {"time-series": 50, "steady-state": 4}


class LogKind(StrEnum):
    """Time series (sampled in time, dynamics visible) or steady-state sweep (one row per operating point)."""

    TIME_SERIES = "time-series"
    STEADY_STATE = "steady-state"


Electrical = Literal["armature", "supply"]


class ColumnSpec(BaseModel):
    """Where a quantity lives in the file and in which unit (see :data:`UNITS`)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    column: str = Field(min_length=1)
    unit: str | None = None  # None: SI (or the unit the header states)


class ReadOptions(BaseModel):
    """How to read a log (every reader, the CLI, the API and the page take the same knobs).

    Attributes:
        columns: quantity -> column (and unit); overrides what the headers say
        kind: ``auto`` detects a steady sweep where the file makes it plain (no time column and a
            strictly monotone command or speed column, one row per step)
        pole_pairs: for electrical speed (eRPM) columns; required when only electrical speed exists
        neutral_us: ESC neutral pulse [us] for a bidirectional ESC; unsigned speed/thrust/torque take
            the sign of ``command - neutral``
        throttle_range_us: (min, max) pulse [us]; the signed command fraction is
            ``(us - neutral) / max(neutral - min, max - neutral)``
        electrical: whose voltage/current the file holds; ``auto``: the supply's when there is an ESC
            command (us or %) or the file is a flight log, else the armature's
        resample: irregular timestamps are put on a uniform grid (``auto``, stated in the notes) or refused
        motor: which motor/ESC of a flight log (ESC instance; output channel ``motor + 1``)
        negate: channels the file holds with the opposite sign to the motor model's (positive voltage drives
            positive current, speed and thrust): negated after reading, stated in the notes
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    columns: dict[str, ColumnSpec] | None = None
    kind: Literal["auto", "time-series", "steady-state"] = "auto"
    pole_pairs: int | None = Field(default=None, ge=1, le=100)
    neutral_us: float = Field(default=1500.0, ge=500.0, le=2500.0)
    throttle_range_us: tuple[float, float] = (1100.0, 1900.0)
    electrical: Literal["auto", "armature", "supply"] = "auto"
    resample: Literal["auto", "refuse"] = "auto"
    motor: int = Field(default=0, ge=0, le=15)
    negate: tuple[Literal["voltage", "current", "omega", "thrust", "torque"], ...] = ()

    @field_validator("negate", mode="before")
    @classmethod
    def _channels(cls, v: Any) -> Any:  # "current,thrust" (a form field, a CLI flag) as a tuple
        return tuple(c.strip() for c in v.split(",") if c.strip()) if isinstance(v, str) else v

    def half_range_us(self) -> float:
        """Full-scale pulse offset [us] from neutral; the range must hold the neutral (a unidirectional ESC:
        neutral = min)."""
        lo, hi = self.throttle_range_us
        if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi and lo <= self.neutral_us <= hi):
            raise LogError("throttle_range_us", f"({lo:g}, {hi:g}) us must hold the neutral {self.neutral_us:g} us "
                                                "(min <= neutral <= max, min < max)")
        return max(self.neutral_us - lo, hi - self.neutral_us)


@dataclass(frozen=True)
class Log:
    """A measurement log in SI.

    Attributes:
        t: time [s], (N,); for steady-state sweeps the row index
        voltage: armature or supply voltage [V] (see ``electrical``), (N,); NaN when absent
        current: armature or supply current [A], (N,); NaN when absent
        omega: rotor speed [rad/s], (N,) (differentiated from theta if only theta was logged)
        theta: rotor angle [rad], (N,) or None when not logged
        thrust: measured thrust [N], (N,); NaN when absent (flight logs)
        kind: time series or steady-state sweep
        source: where it came from (file name), for reports
        torque: measured reaction torque [N m], (N,) or None
        command: signed command fraction [-1, 1] (ESC pulse or throttle), (N,) or None
        electrical: ``armature`` or ``supply`` -- whose voltage and current these are
        absent: which of voltage/current/thrust the file lacks (NaN-filled)
        notes: what the reader did (units read, signs taken from the command, resampling), for the answer
    """

    t: np.ndarray
    voltage: np.ndarray
    current: np.ndarray
    omega: np.ndarray
    theta: np.ndarray | None
    thrust: np.ndarray
    kind: LogKind = LogKind.TIME_SERIES
    source: str = "log"
    torque: np.ndarray | None = None
    command: np.ndarray | None = None
    electrical: Electrical = "armature"
    absent: frozenset[str] = frozenset()
    notes: tuple[str, ...] = field(default=())

    @property
    def n(self) -> int:
        return int(self.t.size)

    @property
    def dt(self) -> float:
        """Sample time [s] of the uniform grid (1.0 for a steady-state sweep)."""
        return float(np.median(np.diff(self.t))) if self.kind is LogKind.TIME_SERIES else 1.0

    @property
    def measured(self) -> frozenset[str]:
        """Channels present: omega always, theta/voltage/current/thrust/torque/command when logged."""
        names = ("theta", "voltage", "current", "thrust", "torque", "command")
        return frozenset(["omega", *(k for k in names if getattr(self, k) is not None and k not in self.absent)])

    def has(self, channel: str) -> bool:
        """Whether ``channel`` was measured (see :attr:`measured`)."""
        return channel in self.measured

    @property
    def complete(self) -> bool:
        """Armature voltage, current, speed and thrust: what the dynamic check (free run) needs."""
        return self.electrical == "armature" and {"voltage", "current", "thrust"} <= self.measured

    def select(self, idx: slice | np.ndarray) -> Log:
        """Rows ``idx`` of every channel."""
        def cut(x: np.ndarray | None) -> np.ndarray | None:
            return None if x is None else x[idx]

        return replace(self, t=self.t[idx], voltage=self.voltage[idx], current=self.current[idx],
                       omega=self.omega[idx], theta=cut(self.theta), thrust=self.thrust[idx],
                       torque=cut(self.torque), command=cut(self.command))

    def columns(self) -> dict[str, np.ndarray]:
        """The channels present, canonical names, SI."""
        out = {"t": self.t}
        for k in ("voltage", "current", "omega", "theta", "thrust", "torque", "command"):
            v = getattr(self, k)
            if v is not None and k in self.measured:
                out[k] = v
        return out


def check_finite(name: str, x: np.ndarray) -> None:
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        raise LogError(name, f"contains NaN or inf (first at row {int(bad[0])})")


def log_from_arrays(
    t: np.ndarray | None, voltage: np.ndarray | None, current: np.ndarray | None, thrust: np.ndarray | None,
    omega: np.ndarray | None = None, theta: np.ndarray | None = None,
    kind: LogKind = LogKind.TIME_SERIES, source: str = "log", *, torque: np.ndarray | None = None,
    command: np.ndarray | None = None, electrical: Electrical = "armature", notes: tuple[str, ...] = (),
) -> Log:
    """Validated :class:`Log` from SI arrays (N,); ``omega`` or ``theta`` (or both) required, the rest optional."""
    arrays = {"omega": omega, "theta": theta, "voltage": voltage, "current": current, "thrust": thrust,
              "torque": torque, "command": command}
    if omega is None and theta is None:
        raise LogError("omega", "missing column; a log needs omega [rad/s] or theta [rad]")
    clean = {k: np.asarray(v, dtype=float).ravel() for k, v in arrays.items() if v is not None}
    ref = "omega" if "omega" in clean else "theta"
    n = clean[ref].size
    if t is None:
        if kind is LogKind.TIME_SERIES:
            raise LogError("t", "missing column; a time series needs t [s] (a steady-state sweep does not: "
                                "say so with steady_state / --steady-state)")
        t = np.arange(n, dtype=float)
    clean["t"] = np.asarray(t, dtype=float).ravel()
    for k, v in clean.items():
        if v.size != n:
            raise LogError(k, f"has {v.size} rows, {ref} has {n}")
        check_finite(k, v)
    if n < MIN_SAMPLES[kind.value]:
        raise LogError("t", f"too short: {n} samples, a {kind.value} log needs at least {MIN_SAMPLES[kind.value]}")
    if kind is LogKind.TIME_SERIES:
        from ocp.logs.timebase import JITTER, steps

        h, jitter = steps(clean["t"])
        if jitter > JITTER:  # the dynamic check integrates on one step: never silently on a median one
            raise LogError("t", f"irregular sample times (steps up to {100 * jitter:.0f} % off the median {h:.3g} s); "
                                "resample them (ocp.logs.timebase.uniform; the file readers do it and say so)")
    w = clean.get("omega")
    if w is None:
        if kind is LogKind.STEADY_STATE:
            raise LogError("omega", "missing column; a steady-state sweep needs omega")
        w = np.gradient(clean["theta"], clean["t"])
    nan = np.full(n, np.nan)
    absent = frozenset(k for k in ("voltage", "current", "thrust") if k not in clean)
    return Log(clean["t"], clean.get("voltage", nan), clean.get("current", nan), w, clean.get("theta"),
               clean.get("thrust", nan), kind, source, clean.get("torque"), clean.get("command"), electrical, absent,
               tuple(notes))
