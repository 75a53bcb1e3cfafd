"""Measurement logs: read rig recordings into one SI table for ``ocp.identify``.

A log has the columns ``t [s], voltage [V], current [A], omega [rad/s] and/or theta [rad],
thrust [N]`` (extra columns ignored). Other names or units are given by a column map
``{"omega": {"column": "speed", "unit": "rpm"}, ...}`` (units: :data:`UNITS`). Formats:

* CSV (header row) and Parquet;
* the Tyto Robotics / RCbenchmark export (``Time (s),ESC signal (µs),...,Thrust (kgf),Voltage (V),
  Current (A),Motor Electrical Speed (RPM),Motor Optical Speed (RPM),...``), see :class:`TytoOptions`;
* steady-state sweeps (one row per operating point, ``t`` optional and meaningless):
  ``kind=LogKind.STEADY_STATE``.

Array layout: every channel shape (N,), SI. Problems raise :class:`~ocp.errors.LogError` naming the
column: missing column, NaN/inf, non-monotonic time, too few samples.
"""

from __future__ import annotations

import csv
import math
import re
from collections.abc import Mapping
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Any, Literal

import numpy as np
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from ocp.errors import LogError

#: quantity -> unit name -> factor to SI (value_SI = factor * value)
UNITS: dict[str, dict[str, float]] = {
    "t": {"s": 1.0, "ms": 1e-3, "us": 1e-6},
    "voltage": {"V": 1.0, "mV": 1e-3},
    "current": {"A": 1.0, "mA": 1e-3},
    "omega": {"rad/s": 1.0, "rpm": 2 * math.pi / 60, "RPM": 2 * math.pi / 60, "rev/s": 2 * math.pi,
              "Hz": 2 * math.pi, "deg/s": math.pi / 180},
    "theta": {"rad": 1.0, "deg": math.pi / 180, "rev": 2 * math.pi},
    "thrust": {"N": 1.0, "mN": 1e-3, "kgf": 9.80665, "gf": 9.80665e-3, "lbf": 4.4482216152605},
}
QUANTITIES: tuple[str, ...] = tuple(UNITS)
MIN_SAMPLES = {"time-series": 50, "steady-state": 4}


class LogKind(StrEnum):
    """Time series (sampled in time, dynamics visible) or steady-state sweep (one row per operating point)."""

    TIME_SERIES = "time-series"
    STEADY_STATE = "steady-state"


class ColumnSpec(BaseModel):
    """Where a quantity lives in the file and in which unit (see :data:`UNITS`)."""

    model_config = ConfigDict(extra="forbid", frozen=True)

    column: str = Field(min_length=1)
    unit: str | None = None  # None: SI


class TytoOptions(BaseModel):
    """How to read a Tyto/RCbenchmark export.

    The export has no signed speed: the sign is taken from the ESC command, ``sign(esc - neutral_us)``
    for a bidirectional (reversing) ESC. The armature voltage is approximated by the supply voltage
    times the signed duty ``(esc - neutral_us) / half_range_us``; the current gets the command sign.
    The electrical speed is divided by ``pole_pairs`` when no optical speed is recorded.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    bidirectional: bool = True
    neutral_us: float = 1500.0
    half_range_us: float = Field(default=500.0, gt=0)
    pole_pairs: int = Field(default=1, ge=1)


@dataclass(frozen=True)
class Log:
    """A measurement log in SI.

    Attributes:
        t: time [s], (N,); for steady-state sweeps the row index
        voltage: command / armature voltage [V], (N,)
        current: measured current [A], (N,)
        omega: rotor speed [rad/s], (N,) (differentiated from theta if only theta was logged)
        theta: rotor angle [rad], (N,) or None when not logged
        thrust: measured thrust [N], (N,)
        kind: time series or steady-state sweep
        source: where it came from (file name), for reports
    """

    t: np.ndarray
    voltage: np.ndarray
    current: np.ndarray
    omega: np.ndarray
    theta: np.ndarray | None
    thrust: np.ndarray
    kind: LogKind = LogKind.TIME_SERIES
    source: str = "log"

    @property
    def n(self) -> int:
        return int(self.t.size)

    @property
    def dt(self) -> float:
        """Median sample time [s] (1.0 for a steady-state sweep)."""
        return float(np.median(np.diff(self.t))) if self.kind is LogKind.TIME_SERIES else 1.0

    def select(self, idx: slice | np.ndarray) -> Log:
        """Rows ``idx`` of every channel."""
        th = None if self.theta is None else self.theta[idx]
        return Log(self.t[idx], self.voltage[idx], self.current[idx], self.omega[idx], th, self.thrust[idx],
                   self.kind, self.source)

    def columns(self) -> dict[str, np.ndarray]:
        out = {"t": self.t, "voltage": self.voltage, "current": self.current, "omega": self.omega,
               "thrust": self.thrust}
        if self.theta is not None:
            out["theta"] = self.theta
        return out


def _check_finite(name: str, x: np.ndarray) -> None:
    bad = np.flatnonzero(~np.isfinite(x))
    if bad.size:
        raise LogError(name, f"contains NaN or inf (first at row {int(bad[0])})")


def log_from_arrays(
    t: np.ndarray | None, voltage: np.ndarray, current: np.ndarray, thrust: np.ndarray,
    omega: np.ndarray | None = None, theta: np.ndarray | None = None,
    kind: LogKind = LogKind.TIME_SERIES, source: str = "log",
) -> Log:
    """Validated :class:`Log` from SI arrays (N,); ``omega`` or ``theta`` (or both) required."""
    arrays = {"voltage": voltage, "current": current, "thrust": thrust, "omega": omega, "theta": theta}
    if omega is None and theta is None:
        raise LogError("omega", "missing column; a log needs omega [rad/s] or theta [rad]")
    clean = {k: np.asarray(v, dtype=float).ravel() for k, v in arrays.items() if v is not None}
    n = clean["voltage"].size
    if t is None:
        if kind is LogKind.TIME_SERIES:
            raise LogError("t", "missing column; a time series needs t [s]")
        t = np.arange(n, dtype=float)
    clean["t"] = np.asarray(t, dtype=float).ravel()
    for k, v in clean.items():
        if v.size != n:
            raise LogError(k, f"has {v.size} rows, voltage has {n}")
        _check_finite(k, v)
    if n < MIN_SAMPLES[kind.value]:
        raise LogError("t", f"too short: {n} samples, a {kind.value} log needs at least {MIN_SAMPLES[kind.value]}")
    if kind is LogKind.TIME_SERIES:
        bad = np.flatnonzero(np.diff(clean["t"]) <= 0)
        if bad.size:
            raise LogError("t", f"must be strictly increasing (row {int(bad[0]) + 1})")
    w = clean.get("omega")
    if w is None:
        if kind is LogKind.STEADY_STATE:
            raise LogError("omega", "missing column; a steady-state sweep needs omega")
        w = np.gradient(clean["theta"], clean["t"])
    return Log(clean["t"], clean["voltage"], clean["current"], w, clean.get("theta"), clean["thrust"], kind, source)


def _to_si(table: Mapping[str, np.ndarray], quantity: str, spec: ColumnSpec) -> np.ndarray:
    if spec.column not in table:
        raise LogError(spec.column, f"missing column (for {quantity}); the file has {sorted(table)}")
    unit = spec.unit or next(iter(UNITS[quantity]))
    if unit not in UNITS[quantity]:
        raise LogError(spec.column, f"unknown unit {unit!r} for {quantity}; use one of {list(UNITS[quantity])}")
    return UNITS[quantity][unit] * np.asarray(table[spec.column], dtype=float)


def _specs(columns: Mapping[str, ColumnSpec | Mapping[str, Any] | str] | None) -> dict[str, ColumnSpec]:
    out = {q: ColumnSpec(column=q) for q in QUANTITIES}
    for q, spec in (columns or {}).items():
        if q not in UNITS:
            raise LogError(q, f"unknown quantity in the column map; use {list(QUANTITIES)}")
        try:
            out[q] = spec if isinstance(spec, ColumnSpec) else (
                ColumnSpec(column=spec) if isinstance(spec, str) else ColumnSpec.model_validate(dict(spec)))
        except ValidationError as exc:
            raise LogError(q, f"bad column spec: {exc.errors()[0]['msg']}") from None
    return out


def log_from_table(
    table: Mapping[str, np.ndarray], columns: Mapping[str, Any] | None = None,
    kind: LogKind = LogKind.TIME_SERIES, source: str = "log",
) -> Log:
    """Log from named numeric columns, mapped and converted by ``columns`` (see module doc)."""
    specs = _specs(columns)
    got = {q: _to_si(table, q, s) for q, s in specs.items() if s.column in table}
    for q in ("voltage", "current", "thrust"):
        if q not in got:
            _to_si(table, q, specs[q])  # raises: missing column
    if "omega" not in got and "theta" not in got:
        raise LogError(specs["omega"].column, f"missing column (need omega or theta); the file has {sorted(table)}")
    return log_from_arrays(got.get("t"), got["voltage"], got["current"], got["thrust"], got.get("omega"),
                           got.get("theta"), kind, source)


def _numeric(name: str, values: list[str]) -> np.ndarray | None:
    try:
        return np.array([float(v) if v.strip() != "" else math.nan for v in values], dtype=float)
    except ValueError:
        return None  # non-numeric column: ignored unless it is needed


def read_table(path: str | Path) -> dict[str, np.ndarray]:
    """Numeric columns of a CSV (header row) or Parquet file; non-numeric columns are dropped."""
    p = Path(path)
    if not p.is_file():
        raise LogError(str(path), "no such file")
    if p.suffix.lower() in (".parquet", ".pq"):
        import pyarrow.parquet as pq

        check_parquet_size(p)
        tab = pq.read_table(p)
        return {str(c): np.asarray(tab.column(c).to_numpy(zero_copy_only=False), dtype=float)
                for c in tab.column_names if tab.schema.field(c).type.num_fields == 0
                and _is_number(str(tab.schema.field(c).type))}
    with p.open(newline="", encoding="utf-8-sig") as fh:
        rows = [r for r in csv.reader(fh) if r]
    if len(rows) < 2:
        raise LogError(p.name, "no data rows")
    header = [h.strip() for h in rows[0]]
    out: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        col = _numeric(name, [r[j] if j < len(r) else "" for r in rows[1:]])
        if col is not None:
            out[name] = col
    return out


#: what a Parquet log may announce in its footer before any of it is decoded (a small file can expand to GBs)
PARQUET_LIMITS = {"rows": 10_000_000, "columns": 1_000, "bytes": 1 << 30}


def check_parquet_size(path: str | Path, max_rows: int = PARQUET_LIMITS["rows"],
                       max_columns: int = PARQUET_LIMITS["columns"], max_bytes: int = PARQUET_LIMITS["bytes"]) -> None:
    """Refuse (:class:`LogError` ``log``) a Parquet file whose metadata announces more than ``max_rows`` rows,
    ``max_columns`` columns or ``max_bytes`` uncompressed bytes: only the footer is read, nothing decoded."""
    import pyarrow.parquet as pq

    meta = pq.ParquetFile(path).metadata
    size = sum(meta.row_group(i).total_byte_size for i in range(meta.num_row_groups))
    for what, n, top in (("rows", meta.num_rows, max_rows), ("columns", meta.num_columns, max_columns),
                         ("uncompressed bytes", size, max_bytes)):
        if n > top:
            raise LogError("log", f"the Parquet file announces {n} {what}; at most {top} accepted")


def _is_number(type_name: str) -> bool:
    return type_name.startswith(("int", "uint", "float", "double", "halffloat"))


_TYTO_UNIT = re.compile(r"^(?P<name>.+?) \((?P<unit>[^)]*)\)$")


def is_tyto(table: Mapping[str, np.ndarray]) -> bool:
    """Whether the columns look like a Tyto/RCbenchmark export."""
    return "Time (s)" in table and any(c.startswith("Thrust (") for c in table) and "ESC signal (µs)" in table


def _tyto_column(table: Mapping[str, np.ndarray], name: str, quantity: str) -> np.ndarray | None:
    for col in table:
        m = _TYTO_UNIT.match(col)
        if m and m["name"] == name:
            return _to_si(table, quantity, ColumnSpec(column=col, unit=m["unit"]))
    return None


def log_from_tyto(table: Mapping[str, np.ndarray], options: TytoOptions | None = None,
                  kind: LogKind = LogKind.TIME_SERIES, source: str = "tyto") -> Log:
    """Log from a Tyto/RCbenchmark export (see :class:`TytoOptions` for the sign and voltage rules)."""
    options = options or TytoOptions()
    esc = np.asarray(table["ESC signal (µs)"], dtype=float)
    sign = np.sign(esc - options.neutral_us) if options.bidirectional else np.ones_like(esc)
    need = {"thrust": "Thrust", "current": "Current", "voltage": "Voltage"}
    got = {}
    for q, name in need.items():
        col = _tyto_column(table, name, q)
        if col is None:
            raise LogError(f"{name} (...)", f"missing column in the Tyto export; it has {sorted(table)}")
        got[q] = col
    speed = _tyto_column(table, "Motor Optical Speed", "omega")
    if speed is None or not np.any(speed != 0):
        speed = _tyto_column(table, "Motor Electrical Speed", "omega")
        if speed is None:
            raise LogError("Motor Optical Speed (RPM)", "missing column: no optical or electrical speed")
        speed = speed / options.pole_pairs
    duty = np.clip((esc - options.neutral_us) / options.half_range_us, -1.0, 1.0)
    volts = got["voltage"] * (duty if options.bidirectional else np.abs(duty))
    t = np.asarray(table["Time (s)"], dtype=float)
    return log_from_arrays(t if kind is LogKind.TIME_SERIES else None, volts, sign * np.abs(got["current"]),
                           got["thrust"], omega=sign * np.abs(speed), kind=kind, source=source)


def read_log(
    path: str | Path, columns: Mapping[str, Any] | None = None, kind: LogKind = LogKind.TIME_SERIES,
    fmt: Literal["auto", "table", "tyto"] = "auto", tyto: TytoOptions | None = None,
) -> Log:
    """Read a CSV/Parquet log (see module doc); ``fmt="auto"`` recognises Tyto exports by their header."""
    table = read_table(path)
    name = Path(path).name
    if fmt == "tyto" or (fmt == "auto" and columns is None and is_tyto(table)):
        return log_from_tyto(table, tyto, kind, name)
    return log_from_table(table, columns, kind, name)


def write_log_csv(log: Log, path: str | Path) -> None:
    """Write a log as CSV in SI with the canonical column names."""
    cols = log.columns()
    with Path(path).open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh, lineterminator="\n")
        w.writerow(list(cols))
        for row in zip(*cols.values(), strict=True):
            w.writerow([repr(float(v)) for v in row])
