"""Named columns -> :class:`~ocp.logs.model.Log`: pick the columns (explicit map, else the headers),
convert to SI, sign unsigned channels by the command, divide electrical speed by the pole pairs,
decide the kind (sweep or time series) and the time base. Every decision lands in ``Log.notes``.

Signs: a bidirectional ESC turns the propeller backwards below its neutral pulse. A speed or torque
column with no negative value, in a file whose command has rows on both sides of neutral, is unsigned:
it takes ``sign(command - neutral)`` (rows at neutral keep the previous sign in a time series). A
measured thrust arbitrates: if it is never negative although the command crosses the neutral, the ESC
is a one-way ESC (neutral not at 1500 us) and nothing is signed -- the notes say so. Supply current and
voltage stay positive: the supply delivers power in both directions.

Sweeps with a time column (a Tyto "PropTest": one row per ESC step, seconds apart) are sweeps too when
the command is strictly monotone and the rows are at least ``SWEEP_ROW_S`` apart: no time series is
logged that slowly. Rows that far apart under a command that is not monotone (a sweep up and back down, a step held
over several rows, or a time in ms under a header without its unit) are refused, naming the time column, until the
user says which kind the file is: read as a time series, an up-and-down sweep was refused as too short to check, or
checked at a row every few seconds (session 72).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from pydantic import ValidationError

from ocp.errors import LogError
from ocp.logs.headers import Header, recognise
from ocp.logs.model import QUANTITIES, UNITS, ColumnSpec, Log, LogKind, ReadOptions, log_from_arrays
from ocp.logs.timebase import HELD, uniform

_SIGNED_BY_COMMAND = ("omega", "torque")
SWEEP_ROW_S = 1.0  # [s] median time between the rows of a steady sweep that has a time column


def column_specs(columns: Mapping[str, Any] | None) -> dict[str, ColumnSpec]:
    """A user's column map ``{quantity: "column" | {"column", "unit"}}`` validated; errors name the quantity."""
    out: dict[str, ColumnSpec] = {}
    for q, spec in (columns or {}).items():
        if q not in UNITS:
            raise LogError(q, f"unknown quantity in the column map; use {list(QUANTITIES)}")
        try:
            out[q] = spec if isinstance(spec, ColumnSpec) else (
                ColumnSpec(column=spec) if isinstance(spec, str) else ColumnSpec.model_validate(dict(spec)))
        except (ValidationError, TypeError, ValueError) as exc:
            msg = exc.errors()[0]["msg"] if isinstance(exc, ValidationError) else str(exc)
            raise LogError(q, f"bad column spec: {msg}") from None
    return out


def _choose(table: Mapping[str, np.ndarray], opt: ReadOptions) -> dict[str, Header]:
    """Quantity -> the column that holds it: the explicit map first, else the best recognised header."""
    found = recognise(list(table))
    chosen: dict[str, Header] = {}
    for q, hs in found.items():
        if q == "omega":  # a mechanical speed with data beats an electrical one
            live = [h for h in hs if np.any(np.nan_to_num(table[h.column]) != 0)] or hs
            hs = sorted(live, key=lambda h: h.electrical)
        elif q == "thrust":  # two force columns (Kg f and N): the SI one
            hs = sorted(hs, key=lambda h: h.unit != "N")
        chosen[q] = hs[0]
    for q, spec in column_specs(opt.columns).items():
        if spec.column not in table:
            raise LogError(spec.column, f"missing column (for {q}); the file has {sorted(table)}")
        unit = spec.unit or next(iter(UNITS[q]))
        if q == "command" and spec.unit is None:
            unit = "fraction"
        if unit not in UNITS[q]:
            raise LogError(spec.column, f"unknown unit {unit!r} for {q}; use one of {list(UNITS[q])}")
        chosen[q] = Header(spec.column, q, unit, unit == "erpm")
    return chosen


def _si(table: Mapping[str, np.ndarray], h: Header) -> np.ndarray:
    return UNITS[h.quantity][h.unit] * np.asarray(table[h.column], dtype=float)


def command_fraction(values: np.ndarray, unit: str, opt: ReadOptions) -> tuple[np.ndarray, str]:
    """Signed command in [-1, 1] from a pulse [us], a throttle [%] or a fraction, and how it was read."""
    if unit == "us":
        half = opt.half_range_us()
        return (values - opt.neutral_us) / half, f"neutral {opt.neutral_us:g} us, +-{half:g} us full scale"
    if unit == "%":
        return values / 100.0, "throttle in %, negative = reverse"
    return values, "signed fraction"


def _directions(u: np.ndarray, kind: LogKind) -> np.ndarray:
    """sign(u) (N,), rows at exactly neutral take the previous sign in a time series (+1 on a sweep)."""
    s = np.sign(u)
    if kind is LogKind.TIME_SERIES:
        idx = np.where(s != 0, np.arange(s.size), 0)
        np.maximum.accumulate(idx, out=idx)
        s = s[idx]
    return np.where(s == 0, 1.0, s)


def _kind(table: Mapping[str, np.ndarray], chosen: Mapping[str, Header], opt: ReadOptions) -> tuple[LogKind, str]:
    if opt.kind != "auto":
        return LogKind(opt.kind), f"{opt.kind} (as told)"
    monotone = False
    if "command" in chosen:
        d = np.diff(np.asarray(table[chosen["command"].column], float))
        monotone = d.size >= 3 and bool(np.all(d > 0) or np.all(d < 0))
    if "t" in chosen:
        t = _si(table, chosen["t"])
        step = float(np.nanmedian(np.diff(t))) if t.size > 1 else 0.0
        if monotone and step >= SWEEP_ROW_S:
            return LogKind.STEADY_STATE, (f"steady-state sweep: {chosen['command'].column!r} is strictly monotone and "
                                          f"the rows are {step:.3g} s apart (one row per operating point; the time "
                                          "column is not used)")
        if step >= SWEEP_ROW_S:  # (neither: a sweep up and back down, a step held over rows, or a time in ms)
            raise LogError(chosen["t"].column, f"rows {step:.3g} s apart: too slow for a time series of a motor's "
                                               "dynamics, and no strictly monotone command marks a steady-state sweep; "
                                               "say which (steady_state / --steady-state: yes, one row per operating "
                                               "point; no, a time series), or give a time in ms a header that says so, "
                                               "e.g. 'time (ms)'")
        return LogKind.TIME_SERIES, f"time series (time column {chosen['t'].column!r})"
    if monotone:
        return LogKind.STEADY_STATE, (f"steady-state sweep: no time column and {chosen['command'].column!r} "
                                      "is strictly monotone (one row per operating point)")
    raise LogError("t", "missing column; a time series needs t [s]. A steady-state sweep (one row per operating "
                        "point) does not: say so with steady_state / --steady-state")


def _speed(table: Mapping[str, np.ndarray], h: Header, opt: ReadOptions, notes: list[str]) -> np.ndarray:
    w = _si(table, h)
    if h.electrical:
        if opt.pole_pairs is None:
            raise LogError(h.column, "is an electrical speed (eRPM); give the motor's pole pairs (pole_pairs, "
                                     "--pole-pairs): read as mechanical it would be pole-pairs times too fast")
        notes.append(f"omega: electrical speed {h.column!r} divided by {opt.pole_pairs} pole pairs")
        return w / opt.pole_pairs
    if opt.pole_pairs is not None:
        notes.append(f"pole_pairs={opt.pole_pairs} not used: {h.column!r} is a mechanical speed")
    return w


def log_from_table(table: Mapping[str, np.ndarray], options: ReadOptions | None = None,
                   source: str = "log") -> Log:
    """Log from named numeric columns (see module doc)."""
    opt = options or ReadOptions()
    chosen = _choose(table, opt)
    if "omega" not in chosen and "theta" not in chosen:
        raise LogError("omega", f"missing column: need omega or theta (a speed such as RPM or an angle); "
                                f"the file has {sorted(table)}")
    kind, how = _kind(table, chosen, opt)
    notes = [f"read as a {how}"]
    notes += [f"{q}: {h.column!r} [{h.unit}]" for q, h in chosen.items()]
    ch: dict[str, np.ndarray] = {q: _si(table, h) for q, h in chosen.items() if q not in ("omega", "command", "t")}
    if "omega" in chosen:
        ch["omega"] = _speed(table, chosen["omega"], opt, notes)
    electrical = opt.electrical
    if "command" in chosen:
        u, read = command_fraction(np.asarray(table[chosen["command"].column], float), chosen["command"].unit, opt)
        ch["command"] = u
        notes.append(f"command {chosen['command'].column!r}: {read}")
        if electrical == "auto":
            electrical = "supply"
            notes.append("voltage and current are the supply's (an ESC drives the motor); say electrical=armature "
                         "if they were measured at the motor")
        sign_by_command(ch, u, kind, electrical, notes)
    electrical = "armature" if electrical == "auto" else electrical
    if "torque" in ch and "omega" in ch and float(np.nansum(ch["torque"] * ch["omega"])) < 0:
        ch["torque"] = -ch["torque"]  # a reaction-torque cell's sign is a mounting convention
        notes.append("torque: sign flipped so that the drag torque has the sign of the speed (the cell's mounting "
                     "convention)")
    t = _si(table, chosen["t"]) if "t" in chosen and kind is LogKind.TIME_SERIES else None
    if t is not None:
        finite = np.flatnonzero(np.all(np.isfinite(np.vstack([t, *ch.values()])), axis=0))
        end = int(finite[-1]) + 1 if finite.size else t.size
        t, ch = t[:end], {k: v[:end] for k, v in ch.items()}  # trailing empty rows of a spreadsheet
        # (a supply's voltage is a sample; the armature's is the drive's, held from row to row)
        t, ch, note = uniform(t, ch, opt.resample == "auto", held=HELD if electrical == "armature" else ("command",))
        if note:
            notes.append(note)
    return log_from_arrays(t, ch.get("voltage"), ch.get("current"), ch.get("thrust"), ch.get("omega"),
                           ch.get("theta"), kind, source, torque=ch.get("torque"), command=ch.get("command"),
                           electrical=electrical, notes=tuple(notes))


def sign_by_command(ch: dict[str, np.ndarray], u: np.ndarray, kind: LogKind, electrical: str,
                     notes: list[str]) -> None:
    """Sign the unsigned channels in place (see module doc)."""
    if not (np.any(u < 0) and np.any(u > 0)):
        return
    f = ch.get("thrust")
    if f is not None and np.nanmax(np.abs(f)) > 0 and np.nanmin(f) >= -0.02 * np.nanmax(np.abs(f)):
        notes.append("the command crosses the neutral but the thrust is never negative: read as a one-way ESC, "
                     "nothing signed (give neutral_us / --neutral-us, the zero-thrust pulse, if it reverses)")
        return
    s = _directions(u, kind)
    names = _SIGNED_BY_COMMAND + (("current", "voltage") if electrical == "armature" else ())
    signed = [q for q in names if q in ch and np.nanmin(ch[q]) >= 0 and np.nanmax(ch[q]) > 0]
    for q in signed:
        ch[q] = s * ch[q]
    if signed:
        notes.append(f"{', '.join(signed)}: unsigned in the file; sign taken from the command (reverse below neutral)")
