"""Flight-controller logs: PX4 ULog (``pyulog``) and ArduPilot DataFlash (``pymavlink``), optional
extra ``[flightlogs]``. One motor's ESC telemetry becomes a time series **without thrust**:

* PX4: ``esc_status`` (``esc[m].esc_rpm`` [rpm], ``esc_current`` [A], ``esc_voltage`` [V]) and the
  command from ``actuator_motors`` (``control[m]``, -1..1; NaN while disarmed -> 0) or else
  ``actuator_outputs`` (``output[m]`` [us]);
* ArduPilot: ``ESC`` messages of ``Instance == m`` (``RPM`` [rpm], ``Curr`` [A], ``Volt`` [V]) and
  ``RCOU`` (``C<m+1>`` [us]).

ESC current and voltage are the supply's (``electrical="supply"``). Topics logged at different rates
are merged onto the ESC topic's grid (:func:`ocp.logs.timebase.merge`, stated in the notes).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from ocp.errors import LogError
from ocp.logs.assemble import command_fraction, sign_by_command
from ocp.logs.model import RPM, Electrical, Log, LogKind, ReadOptions, log_from_arrays
from ocp.logs.timebase import merge

Topics = dict[str, tuple[np.ndarray, dict[str, np.ndarray]]]


def _needs(module: str, p: Path) -> LogError:
    return LogError(p.name, f"reading this log needs {module}: pip install 'thrustshape[flightlogs]'")


def _ulog_topics(p: Path, m: int) -> tuple[Topics, str]:
    try:
        from pyulog import ULog
    except ImportError:
        raise _needs("pyulog", p) from None
    try:
        ulog = ULog(str(p), ["esc_status", "actuator_motors", "actuator_outputs"], True)
    except Exception as exc:  # pyulog raises bare exceptions on a damaged file
        raise LogError(p.name, f"cannot be read as a PX4 ULog: {type(exc).__name__}: {exc}") from None
    data = {(d.name, d.multi_id): d.data for d in ulog.data_list}
    esc = data.get(("esc_status", 0))
    if esc is None or f"esc[{m}].esc_rpm" not in esc:
        raise LogError("esc_status", f"no esc_status topic with motor {m} (esc[{m}].esc_rpm) in this ULog")
    topics: Topics = {"esc_status": (esc["timestamp"] * 1e-6, {
        "omega": esc[f"esc[{m}].esc_rpm"] * RPM, "current": esc[f"esc[{m}].esc_current"],
        "voltage": esc[f"esc[{m}].esc_voltage"]})}
    unit = "fraction"
    if ("actuator_motors", 0) in data and f"control[{m}]" in data[("actuator_motors", 0)]:
        d = data[("actuator_motors", 0)]
        topics["actuator_motors"] = (d["timestamp"] * 1e-6, {"command": np.nan_to_num(d[f"control[{m}]"])})
    elif ("actuator_outputs", 0) in data and f"output[{m}]" in data[("actuator_outputs", 0)]:
        d = data[("actuator_outputs", 0)]
        topics["actuator_outputs"] = (d["timestamp"] * 1e-6, {"command": d[f"output[{m}]"]})
        unit = "us"
    return topics, unit


def _dataflash_topics(p: Path, m: int) -> tuple[Topics, str]:
    try:
        from pymavlink.DFReader import DFReader_binary
    except ImportError:
        raise _needs("pymavlink", p) from None
    rows: dict[str, list[tuple[float, ...]]] = {"ESC": [], "RCOU": []}
    try:
        with DFReader_binary(str(p)) as reader:
            while (msg := reader.recv_match(type=["ESC", "RCOU"])) is not None:
                rows_for(msg, m, rows)
    except Exception as exc:  # pymavlink raises bare exceptions on a damaged file
        raise LogError(p.name, f"cannot be read as an ArduPilot DataFlash log: {type(exc).__name__}: {exc}") from None
    if not rows["ESC"]:
        raise LogError("ESC", f"no ESC messages with Instance {m} in this DataFlash log")
    esc = np.array(rows["ESC"], dtype=float)
    topics: Topics = {"ESC": (esc[:, 0], {"omega": esc[:, 1] * RPM, "voltage": esc[:, 2], "current": esc[:, 3]})}
    if rows["RCOU"]:
        rc = np.array(rows["RCOU"], dtype=float)
        topics["RCOU"] = (rc[:, 0], {"command": rc[:, 1]})
    return topics, "us"


def rows_for(msg: Any, m: int, rows: dict[str, list[tuple[float, ...]]]) -> None:
    """Append one DataFlash ESC/RCOU message of motor ``m`` as (t [s], values...)."""
    name = msg.get_type()
    if name == "ESC" and int(msg.Instance) == m:
        rows["ESC"].append((msg.TimeUS * 1e-6, float(msg.RPM), float(msg.Volt), float(msg.Curr)))
    elif name == "RCOU" and hasattr(msg, f"C{m + 1}"):
        rows["RCOU"].append((msg.TimeUS * 1e-6, float(getattr(msg, f"C{m + 1}"))))


def _dedupe(topics: Topics) -> Topics:
    """Drop repeated timestamps (a topic logged twice in one tick keeps its first sample)."""
    out: Topics = {}
    for name, (t, ch) in topics.items():
        keep = np.concatenate([[True], np.diff(t) > 0])
        out[name] = (t[keep], {k: v[keep] for k, v in ch.items()})
    return out


def read_flight_log(p: Path, fmt: str, opt: ReadOptions) -> Log:
    """One motor of a PX4 ULog (``fmt="ulog"``) or ArduPilot DataFlash log (``"dataflash"``) as a Log."""
    if not p.is_file():
        raise LogError(str(p), "no such file")
    topics, unit = _ulog_topics(p, opt.motor) if fmt == "ulog" else _dataflash_topics(p, opt.motor)
    reference = next(iter(topics))
    # (the ESC's voltage is the supply's, a sample; its command is held)
    t, ch, notes = merge(_dedupe(topics), reference, opt.resample == "auto", held=("command",))
    kind = LogKind.STEADY_STATE if opt.kind == "steady-state" else LogKind.TIME_SERIES
    notes = [f"{'PX4 ULog' if fmt == 'ulog' else 'ArduPilot DataFlash log'}, motor {opt.motor}: ESC speed, "
             "current and voltage (the supply's); no thrust is logged in flight", *notes]
    if "command" in ch:
        u, how = command_fraction(ch["command"], unit, opt)
        ch["command"] = u
        notes.append(f"command from {list(topics)[-1]}: {how}")
        sign_by_command(ch, u, kind, "supply", notes)
    electrical: Electrical = "armature" if opt.electrical == "armature" else "supply"
    return log_from_arrays(t if kind is LogKind.TIME_SERIES else None, ch["voltage"], ch["current"], None,
                           ch["omega"], None, kind, p.name, command=ch.get("command"), electrical=electrical,
                           notes=tuple(notes))
