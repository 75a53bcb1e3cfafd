"""Measurement logs: read rig recordings and flight logs into one SI table for ``ocp.identify``.

A log has the channels ``t [s], voltage [V], current [A], omega [rad/s] and/or theta [rad],
thrust [N]``, optionally ``torque [N m]`` and ``command`` (signed fraction); any of voltage,
current, thrust may be missing (:attr:`Log.measured`), and voltage/current may be the supply's
(:attr:`Log.electrical`). Formats, by file suffix:

* CSV (``pyarrow.csv``), Parquet, Excel ``.xlsx`` (optional extra ``[xlsx]``), MATLAB ``.mat``:
  columns recognised by their headers with units (:mod:`ocp.logs.headers`: Tyto/RCbenchmark
  exports, vendor performance sweeps, ``name (unit)``, ``name_unit``, canonical SI names) or mapped
  by ``columns={"omega": {"column": "speed", "unit": "rpm"}, ...}`` (units: :data:`UNITS`);
* PX4 ULog ``.ulg`` and ArduPilot DataFlash ``.bin`` (optional extra ``[flightlogs]``,
  :mod:`ocp.logs.flight`): ESC speed, current, voltage and the motor command, no thrust.

Steady-state sweeps (one row per operating point) are detected where the file makes it plain
(no time column, strictly monotone command) or told by ``kind``. Irregular timestamps are resampled
onto a uniform grid (stated in :attr:`Log.notes`) or refused (:mod:`ocp.logs.timebase`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal

from ocp.errors import LogError
from ocp.logs.assemble import column_specs, command_fraction, log_from_table
from ocp.logs.bounds import check_parquet_size, check_size
from ocp.logs.model import (
    MIN_SAMPLES,
    QUANTITIES,
    UNITS,
    ColumnSpec,
    Log,
    LogKind,
    ReadOptions,
    check_finite,
    log_from_arrays,
)
from ocp.logs.tables import read_table
from ocp.logs.writers import write_log_csv, write_reference_mat

__all__ = ["MIN_SAMPLES", "QUANTITIES", "UNITS", "ColumnSpec", "Log", "LogKind", "ReadOptions", "check_finite",
           "check_parquet_size", "check_size",
           "column_specs", "command_fraction", "log_from_arrays", "log_from_table", "negated", "read_log", "read_table",
           "write_log_csv", "write_reference_mat"]

Format = Literal["auto", "table", "ulog", "dataflash"]
FLIGHT_SUFFIXES = {".ulg": "ulog", ".bin": "dataflash"}  # a DataFlash ".log" is text: not read


def read_log(
    path: str | Path, columns: Mapping[str, Any] | None = None, kind: LogKind | str | None = None,
    fmt: Format = "auto", options: ReadOptions | None = None,
) -> Log:
    """Read a log file (see module doc). ``columns`` and ``kind`` override those of ``options``."""
    opt = options or ReadOptions()
    update: dict[str, Any] = {}
    if columns is not None:
        update["columns"] = column_specs(columns)
    if kind is not None:
        update["kind"] = LogKind(kind).value
    if update:
        opt = opt.model_copy(update=update)
    p = Path(path)
    flight = FLIGHT_SUFFIXES.get(p.suffix.lower()) if fmt == "auto" else (fmt if fmt != "table" else None)
    if flight is not None:
        from ocp.logs.flight import read_flight_log

        if opt.columns:
            raise LogError("columns", "a column map applies to tables (CSV, Parquet, .xlsx, .mat), not to flight logs")

        return negated(read_flight_log(p, flight, opt), opt.negate)
    return negated(log_from_table(read_table(p), opt, p.name), opt.negate)


def negated(log: Log, channels: Sequence[str]) -> Log:
    """``log`` with ``channels`` negated (the rotor angle with the speed), stated in its notes
    (:attr:`ReadOptions.negate`)."""
    if not channels:
        return log
    flip: dict[str, Any] = {c: -v for c in dict.fromkeys(channels) if (v := getattr(log, c)) is not None}
    if "omega" in flip and log.theta is not None:
        flip["theta"] = -log.theta
    return replace(log, **flip, notes=(*log.notes, f"negated as asked: {', '.join(dict.fromkeys(channels))}"))
