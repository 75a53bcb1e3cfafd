"""Unit-aware header parsing: which column holds which quantity, in which unit.

A header is ``name (unit)``, ``name [unit]``, ``name_unit`` or a bare canonical SI name (``t``,
``voltage``, ``omega``, ...; another bare name such as ``force`` has no unit to trust and is left to
the column map; ``RPM`` is a unit used as a name). The unit decides the
family (time, pulse, speed, force, torque, voltage, current) and the name settles what units alone
cannot: ``us`` is a time in ``Time (us)`` but an ESC pulse in ``ESC (µs)``; ``kg`` is a force under
``Thrust`` or ``Force``. Recognised, among others, the Tyto/RCbenchmark export (``Time (s), ESC (µs),
Servo (µs), Torque (N·m), Thrust (kgf), Voltage (V), Current (A), Motor Optical Speed (RPM), Motor
Electrical Speed (RPM)``, and ``ESC signal (µs)``), vendor performance sweeps (``PWM (µs), RPM,
Current (A), Voltage (V), Power (W), Force (Kg f), Efficiency (g/W), Force (N)``) and the canonical SI
names (``t, voltage, current, omega, theta, thrust, torque, command``).
"""

from __future__ import annotations

import re
from dataclasses import dataclass

#: normalised unit text -> (family, unit name of ocp.logs.model.UNITS)
_UNIT_ALIASES: dict[str, tuple[str, str]] = {
    "s": ("time", "s"), "sec": ("time", "s"), "ms": ("time", "ms"), "us": ("time-or-pulse", "us"),
    "%": ("throttle", "%"),
    "rpm": ("speed", "rpm"), "erpm": ("speed", "erpm"), "rad/s": ("speed", "rad/s"), "rev/s": ("speed", "rev/s"),
    "rps": ("speed", "rev/s"), "hz": ("speed", "Hz"), "deg/s": ("speed", "deg/s"),
    "rad": ("angle", "rad"), "deg": ("angle", "deg"), "rev": ("angle", "rev"),
    "n": ("force", "N"), "mn": ("force", "mN"), "kgf": ("force", "kgf"), "kg": ("force", "kgf"),
    "kg f": ("force", "kgf"), "gf": ("force", "gf"), "g": ("force", "gf"), "lbf": ("force", "lbf"),
    "lb": ("force", "lbf"), "ozf": ("force", "ozf"), "oz": ("force", "ozf"),
    "n m": ("torque", "N m"), "nm": ("torque", "N m"), "mn m": ("torque", "mN m"), "mnm": ("torque", "mN m"),
    "kgf cm": ("torque", "kgf cm"), "ozf in": ("torque", "ozf in"), "oz in": ("torque", "ozf in"),
    "v": ("voltage", "V"), "mv": ("voltage", "mV"), "a": ("current", "A"), "ma": ("current", "mA"),
    "w": ("power", "W"), "g/w": ("efficiency", "g/W"),
}
_IGNORED = ("servo", "efficien", "temperat", "temp ", "vibration", "acc", "pressure", "power", "settling", "message")
_NAME_KEYS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("t", ("time", "timestamp")),
    ("torque", ("torque",)),
    ("thrust", ("thrust", "force", "lift")),
    ("omega", ("speed", "rpm", "omega", "velocity", "rotation")),
    ("theta", ("theta", "angle", "position")),
    ("voltage", ("voltage", "volt")),
    ("current", ("current", "curr", "amp")),
    ("command", ("esc", "pwm", "throttle", "signal", "command", "cmd", "duty", "input", "output")),
)
_SI_DEFAULT = {"t": "s", "voltage": "V", "current": "A", "omega": "rad/s", "theta": "rad", "thrust": "N",
               "torque": "N m", "command": "fraction"}
_FAMILY_QUANTITY = {"time": "t", "speed": "omega", "angle": "theta", "force": "thrust", "torque": "torque",
                    "voltage": "voltage", "current": "current", "throttle": "command"}
_BRACKETS = re.compile(r"^(?P<name>.*?)\s*[(\[]\s*(?P<unit>[^)\]]*?)\s*[)\]]\s*$")


@dataclass(frozen=True)
class Header:
    """What one column holds.

    Attributes:
        column: the header as written in the file
        quantity: one of ``t, voltage, current, omega, theta, thrust, torque, command``
        unit: a unit name of :data:`ocp.logs.model.UNITS` for that quantity
        electrical: an electrical speed (eRPM: divide by the pole pairs)
    """

    column: str
    quantity: str
    unit: str
    electrical: bool = False


def normalise_unit(text: str) -> str:
    """Lower-case unit text with micro signs as ``u`` and products as one space: ``N·m`` -> ``n m``."""
    u = text.strip().replace("µ", "u").replace("μ", "u").lower()
    u = re.sub(r"[·*.\-_]", " ", u.replace("kg f", "kgf").replace("kg-f", "kgf"))
    u = re.sub(r"\s+", " ", u).strip()
    return {"nm": "nm", "n m": "n m"}.get(u, u)


def _split(column: str) -> tuple[str, str | None]:
    m = _BRACKETS.match(column.strip())
    if m:
        return m["name"].strip().lower(), m["unit"]
    head, _, tail = column.strip().rpartition("_")
    if head and normalise_unit(tail) in _UNIT_ALIASES:
        return head.lower(), tail
    return column.strip().lower(), None


def _by_name(name: str) -> str | None:
    if name in ("t", "voltage", "current", "omega", "theta", "thrust", "torque", "command"):
        return name
    words = f" {name} "
    for q, keys in _NAME_KEYS:
        if any(k in words for k in keys):
            return q
    return None


def parse_header(column: str) -> Header | None:
    """The quantity and unit of one header, or None when it is not one thrustshape uses."""
    name, unit_text = _split(column)
    if any(k in f"{name} " for k in _IGNORED) or name.startswith("acc"):
        return None
    electrical = "electrical" in name or "erpm" in name.replace("-", "")
    if unit_text is None:  # no unit: only the canonical SI names and speed units used as names ("RPM")
        if normalise_unit(name) in ("rpm", "erpm"):
            return Header(column, "omega", "erpm" if electrical else "rpm", electrical)
        if name in _SI_DEFAULT:
            return Header(column, name, _SI_DEFAULT[name])
        return None
    family_unit = _UNIT_ALIASES.get(normalise_unit(unit_text))
    if family_unit is None:
        return None
    family, unit = family_unit
    by_name = _by_name(name)
    if family == "time-or-pulse":
        return Header(column, "t", "us") if by_name == "t" else Header(column, "command", "us")
    if family in ("power", "efficiency"):
        return None
    q = _FAMILY_QUANTITY[family]
    if family == "force" and by_name != "thrust":
        return None  # "AccX (g)", "Weight (g)": a force column must say thrust, force or lift
    if family == "speed" and electrical:
        unit = "erpm" if unit in ("rpm", "erpm") else unit
    return Header(column, q, unit, electrical and q == "omega")


def recognise(columns: list[str]) -> dict[str, list[Header]]:
    """Quantity -> the columns that hold it, in file order."""
    out: dict[str, list[Header]] = {}
    for c in columns:
        h = parse_header(c)
        if h is not None:
            out.setdefault(h.quantity, []).append(h)
    return out
