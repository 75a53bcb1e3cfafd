"""Motor-propeller parameters: validation, unit conversion at load, presets.

All values are SI inside thrustshape (rad/s, N, N*m, A, V, H, Ohm, kg*m^2). A parameter file is JSON
or YAML with the keys ``J, B, c_tau, c_f, k_t, k_e, R, L`` and optionally

* ``units``: ``{"c_f": "N/Hz^2" | "N/rpm^2" | "N/(rad/s)^2", "c_tau": "N*m/Hz^2" | ...}`` -- the
  per-speed-squared unit in which ``c_f`` / ``c_tau`` are given; converted once, at load, to
  per (rad/s)^2. "Hz" means revolutions per second (1 Hz = 2*pi rad/s).
* ``name`` and ``notes``: free-text metadata, kept but never used in computation.
* ``effects``: the effect block of a calibrated file (``ocp.model.effects.load_plant`` reads it); ignored
  here, so a calibrated file still loads as plain :class:`MotorParams`.

Anything else is an error that names the key.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from functools import cache
from importlib import resources
from pathlib import Path
from typing import Any

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from ocp.errors import ParameterError

#: built-in parameter sets: the seed paper's rig with its "Hz" read as rad/s (the default, ``paper-rig``) or as
#: rev/s (``paper-rig-revs``); the paper is inconsistent, see the presets' notes and :mod:`ocp.presets.evidence`
PRESETS: tuple[str, ...] = ("paper-rig", "paper-rig-revs")

#: per-speed-squared units accepted in the ``units`` block -> factor that turns "per unit^2" into
#: "per (rad/s)^2" (divide by (rad/s per unit)^2).
_SPEED_UNITS: dict[str, float] = {
    "(rad/s)^2": 1.0,
    "hz^2": (2.0 * math.pi) ** 2,
    "(rev/s)^2": (2.0 * math.pi) ** 2,
    "rpm^2": (2.0 * math.pi / 60.0) ** 2,
}
_UNIT_KEYS = {"c_f": "N", "c_tau": "N*m"}


class MotorParams(BaseModel):
    """DC motor + fixed-pitch bidirectional propeller (paper eqs. dc_mechanical, dc_electrical).

    Attributes (SI):
        J: rotor + propeller inertia [kg m^2]
        B: viscous friction [N m s/rad] (>= 0, as in the paper)
        c_tau: quadratic drag torque coefficient [N m s^2/rad^2]
        c_f: thrust coefficient [N s^2/rad^2]
        k_t: torque constant [N m/A]
        k_e: back-emf constant [V s/rad]
        R: armature resistance [Ohm]
        L: armature inductance [H]
    """

    model_config = ConfigDict(frozen=True, extra="forbid")

    J: float = Field(gt=0, allow_inf_nan=False)
    B: float = Field(ge=0, allow_inf_nan=False)
    c_tau: float = Field(gt=0, allow_inf_nan=False)
    c_f: float = Field(gt=0, allow_inf_nan=False)
    k_t: float = Field(gt=0, allow_inf_nan=False)
    k_e: float = Field(gt=0, allow_inf_nan=False)
    R: float = Field(gt=0, allow_inf_nan=False)
    L: float = Field(gt=0, allow_inf_nan=False)

    # eq:current_reference  i_d = a1 w' + a2 w + a3 w|w|
    @property
    def current_coefficients(self) -> tuple[float, float, float]:
        """(a1 [A s^2/rad], a2 [A s/rad], a3 [A s^2/rad^2]) of eq. current_reference."""
        return self.J / self.k_t, self.B / self.k_t, self.c_tau / self.k_t

    # eq:voltage_reference  V_d = b1 w'' + b2 w' + b3 w + b4 w|w| + b5 |w| w'
    @property
    def voltage_coefficients(self) -> tuple[float, float, float, float, float]:
        """(b1, b2, b3, b4, b5) of eq. voltage_reference, SI."""
        J, B, c, kt, R, L = self.J, self.B, self.c_tau, self.k_t, self.R, self.L
        return (L * J / kt, (L * B + R * J) / kt, self.k_e + R * B / kt, R * c / kt, 2.0 * L * c / kt)

    @property
    def k(self) -> float:
        """Normalised drag k = c_tau / J [1/rad] of eq. omega_dyn."""
        return self.c_tau / self.J

    def max_steady_speed(self, voltage: float) -> float:
        """Steady speed [rad/s] reached under constant ``voltage`` [V] > 0 (positive root)."""
        # k_t (V - k_e w)/R = B w + c_tau w^2  ->  c_tau w^2 + (B + k_t k_e/R) w - k_t V/R = 0
        b = self.B + self.k_t * self.k_e / self.R
        return (-b + math.sqrt(b * b + 4.0 * self.c_tau * self.k_t * voltage / self.R)) / (2.0 * self.c_tau)


def _convert_units(raw: dict[str, Any], units: Any) -> None:
    if not isinstance(units, Mapping):
        raise ParameterError("units", "must be a mapping like {'c_f': 'N/Hz^2'}")
    for key, unit in units.items():
        if key not in _UNIT_KEYS:
            raise ParameterError(f"units.{key}", f"unknown key; units can be given for {sorted(_UNIT_KEYS)}")
        if not isinstance(unit, str):
            raise ParameterError(f"units.{key}", "must be a string such as 'N/Hz^2'")
        norm = unit.replace(" ", "").replace("·", "*").lower()
        head, _, speed = norm.partition("/")
        if head != _UNIT_KEYS[key].lower() or speed not in _SPEED_UNITS:
            allowed = ", ".join(f"{_UNIT_KEYS[key]}/{s}" for s in _SPEED_UNITS)
            raise ParameterError(f"units.{key}", f"unknown unit {unit!r}; use one of {allowed}")
        if key in raw and isinstance(raw[key], int | float):
            raw[key] = float(raw[key]) / _SPEED_UNITS[speed]


def params_from_mapping(data: Mapping[str, Any]) -> MotorParams:
    """Validate a mapping of parameters (see module doc); raises :class:`ParameterError`."""
    if not isinstance(data, Mapping):
        raise ParameterError("params", "must be a mapping of parameter names to values")
    raw = {k: v for k, v in data.items() if k not in ("units", "name", "notes", "effects")}
    if "units" in data:
        _convert_units(raw, data["units"])
    try:
        return MotorParams(**raw)
    except ValidationError as exc:
        err = exc.errors()[0]
        key = ".".join(str(p) for p in err["loc"]) or "params"
        reason = {"extra_forbidden": "unknown key", "missing": "missing key"}.get(err["type"], err["msg"])
        raise ParameterError(key, reason) from None


@cache
def preset(name: str) -> MotorParams:
    """Built-in parameter set by name (see :data:`PRESETS`); read once, then cached (it is frozen)."""
    if name not in PRESETS:
        raise ParameterError("params", f"unknown preset {name!r}; presets are {list(PRESETS)}")
    text = resources.files("ocp.presets").joinpath(f"{name}.json").read_text(encoding="utf-8")
    return params_from_mapping(json.loads(text))


def load_params(source: str | Path | Mapping[str, Any]) -> MotorParams:
    """Parameters from a preset name, a JSON/YAML file path, or a mapping."""
    if isinstance(source, Mapping):
        return params_from_mapping(source)
    if isinstance(source, str) and source in PRESETS:
        return preset(source)
    return params_from_mapping(read_mapping(source))


def read_mapping(source: str | Path) -> dict[str, Any]:
    """The mapping stored in a JSON (``.json``) or YAML parameter file; errors name ``params``."""
    path = Path(source)
    if not path.is_file():
        raise ParameterError("params", f"no preset or file named {str(source)!r}; presets are {list(PRESETS)}")
    text = path.read_text(encoding="utf-8")
    try:
        data = json.loads(text) if path.suffix.lower() == ".json" else yaml.safe_load(text)
    except (json.JSONDecodeError, yaml.YAMLError) as exc:
        raise ParameterError("params", f"{path.name} is not valid JSON/YAML: {exc}") from None
    if not isinstance(data, dict):
        raise ParameterError("params", f"{path.name} must hold a mapping")
    return data
