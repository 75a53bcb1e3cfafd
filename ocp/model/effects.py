"""Effect catalogue: the physics the nominal motor model (paper eqs. dc_mechanical, dc_electrical,
thrust_model) leaves out, each a named, documented term usable by :class:`ocp.model.plant.DCMotorPlant`
in numpy simulation *and* CasADi collocation (every hook is written with the ``ops`` backend).

Sign functions are smoothed: ``sign(w) ~ tanh(w / omega_eps)`` (``omega_eps`` [rad/s], a fixed
shape parameter, never fitted). Inside an optimiser phase the sign of ``w`` is known and passed as
``sign``; the effects then use it exactly, so the phase NLP stays smooth.

Each effect class records: the channel it acts on (the residual in which it shows), the units of
its parameters, which parameters are fitted, their bounds and a starting guess, and the residual
*signature* that gives it away. Parameter file format (JSON/YAML)::

    {"J": ..., "B": ..., ..., "L": ...,                 # MotorParams keys (see ocp.model.params)
     "effects": {"coulomb_friction": {"tau_c": 0.002}, "thrust_lag": {"tau": 0.03}}}

Unknown effect names or parameters are :class:`~ocp.errors.ParameterError` naming the key.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, ClassVar

from ocp.errors import ParameterError
from ocp.model.effect_base import Channel, EffectBase, check_range, require_positive, reverse_weight, smooth_sign
from ocp.model.params import PRESETS, MotorParams, load_params, params_from_mapping, read_mapping
from ocp.model.plant import DCMotorPlant, Effect, Expr, Ops, effect_states
from ocp.model.stateful_effects import Cogging, InputDelay, StatefulBase, ThrustLag


@dataclass(frozen=True)
class CoulombFriction(EffectBase):
    """Dry (Coulomb) friction of brushes and bearings: a constant torque opposing rotation.

    ``tau = tau_c tanh(w / omega_eps)`` [N m].
    """

    tau_c: float = 0.0
    omega_eps: float = 0.5
    name: ClassVar[str] = "coulomb_friction"
    channel: ClassVar[Channel] = "mechanical"
    units: ClassVar[dict[str, str]] = {"tau_c": "N m", "omega_eps": "rad/s"}
    fitted: ClassVar[tuple[str, ...]] = ("tau_c",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"tau_c": (0.0, 0.1)}
    guess: ClassVar[dict[str, float]] = {"tau_c": 1e-3}
    signature: ClassVar[str] = ("torque residual is a step with the sign of the speed, same size at every speed; "
                                "the free-run speed undershoots in both directions")

    def load_torque(self, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        return self.tau_c * smooth_sign(omega, self.omega_eps, ops, sign)

    def breakaway(self) -> float:
        return self.tau_c


@dataclass(frozen=True)
class Stribeck(EffectBase):
    """Stribeck breakaway friction: extra torque near zero speed that vanishes as the film builds.

    ``tau = tau_s exp(-|w/omega_s|^delta) tanh(w/omega_eps)`` [N m]; ``delta`` (a shape, not fitted) 2 by default
    (Gaussian, Armstrong's), 1 is Tustin's exponential decay, smaller ones decay more slowly. For ``delta`` other
    than 2, ``|r|^delta`` (``r = w / omega_s``) is written ``(r^2 + e^2)^(delta/2)`` with ``e = omega_eps /
    omega_s``: smooth at zero speed for the optimiser, where the sign's smoothing holds the torque near zero anyway;
    beyond ``omega_eps`` the exponent is off by under ``delta e^2 / (2 |r|^(2 - delta))``.
    """

    tau_s: float = 0.0
    omega_s: float = 2.0
    omega_eps: float = 0.5
    delta: float = 2.0
    name: ClassVar[str] = "stribeck"
    channel: ClassVar[Channel] = "mechanical"
    units: ClassVar[dict[str, str]] = {"tau_s": "N m", "omega_s": "rad/s", "omega_eps": "rad/s", "delta": "1"}
    fitted: ClassVar[tuple[str, ...]] = ("tau_s", "omega_s")
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"tau_s": (0.0, 0.1), "omega_s": (0.3, 30.0)}
    guess: ClassVar[dict[str, float]] = {"tau_s": 1e-3, "omega_s": 3.0}
    signature: ClassVar[str] = ("torque residual with the sign of the speed only at low speed (near reversals), "
                                "absent in the high-speed band; the rotor sticks before it reverses")

    def __post_init__(self) -> None:
        require_positive("stribeck.omega_s", self.omega_s)
        require_positive("stribeck.delta", self.delta)

    def load_torque(self, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        r = omega / self.omega_s
        if self.delta == 2.0:
            decay = r * r
        else:
            e = self.omega_eps / self.omega_s
            decay = (r * r + e * e) ** (0.5 * self.delta)
        return self.tau_s * ops.exp(-decay) * smooth_sign(omega, self.omega_eps, ops, sign)

    def breakaway(self) -> float:
        return self.tau_s


@dataclass(frozen=True)
class DragAsymmetry(EffectBase):
    """Direction-dependent propeller drag: reverse rotation drags by ``c_tau + dc_tau``.

    ``tau = dc_tau w|w| rev(w)`` [N m] with ``rev`` the smooth reverse-rotation indicator.
    """

    dc_tau: float = 0.0
    omega_eps: float = 0.5
    name: ClassVar[str] = "drag_asymmetry"
    channel: ClassVar[Channel] = "mechanical"
    units: ClassVar[dict[str, str]] = {"dc_tau": "N m s^2/rad^2", "omega_eps": "rad/s"}
    fitted: ClassVar[tuple[str, ...]] = ("dc_tau",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"dc_tau": (-1e-3, 1e-3)}
    guess: ClassVar[dict[str, float]] = {"dc_tau": 0.0}
    signature: ClassVar[str] = ("torque residual growing with speed squared in reverse rotation only; "
                                "the free-run reverse speed is off while the forward one fits")

    def load_torque(self, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        ww = sign * omega * omega if sign is not None else omega * ops.abs(omega)
        return self.dc_tau * ww * reverse_weight(omega, self.omega_eps, ops, sign)


@dataclass(frozen=True)
class ThrustAsymmetry(EffectBase):
    """Direction-dependent thrust: a cambered blade pushes ``c_f + dc_f`` in reverse.

    ``F += dc_f w|w| rev(w)`` [N].
    """

    dc_f: float = 0.0
    omega_eps: float = 0.5
    name: ClassVar[str] = "thrust_asymmetry"
    channel: ClassVar[Channel] = "thrust"
    units: ClassVar[dict[str, str]] = {"dc_f": "N s^2/rad^2", "omega_eps": "rad/s"}
    fitted: ClassVar[tuple[str, ...]] = ("dc_f",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"dc_f": (-1e-2, 1e-2)}
    guess: ClassVar[dict[str, float]] = {"dc_f": 0.0}
    signature: ClassVar[str] = ("thrust residual proportional to speed squared for negative thrust only; "
                                "speed and current fit in both directions")

    def thrust(self, thrust: Expr, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        ww = sign * omega * omega if sign is not None else omega * ops.abs(omega)
        return thrust + self.dc_f * ww * reverse_weight(omega, self.omega_eps, ops, sign)


@dataclass(frozen=True)
class ForceOffset(EffectBase):
    """Force-sensor zero offset (tare drift, cable preload): ``F += f0`` [N]."""

    f0: float = 0.0
    name: ClassVar[str] = "force_offset"
    channel: ClassVar[Channel] = "thrust"
    units: ClassVar[dict[str, str]] = {"f0": "N"}
    fitted: ClassVar[tuple[str, ...]] = ("f0",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"f0": (-10.0, 10.0)}
    guess: ClassVar[dict[str, float]] = {"f0": 0.0}
    signature: ClassVar[str] = "constant thrust residual, also at zero speed, same in both directions"

    def thrust(self, thrust: Expr, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        return thrust + self.f0


#: the sharpness of a gap dead band's smooth step (:class:`VoltageDeadband`): its output rises from 2 % to 98 % of
#: the command between 0.95 and 1.05 times the band (at 4, 6 % to 98 % over 0.8-1.25, a PI loop's command waiting
#: at 0.9 times the band, where a drive with a minimum pulse puts out nothing, would put out 18 % of it)
GAP_EDGE = 20.0


@dataclass(frozen=True)
class VoltageDeadband(EffectBase):
    """Driver dead band (H-bridge dead time, PWM minimum pulse): small commands do not reach the motor.

    Two forms, ``gap`` a fixed shape (never fitted). ``gap = 0`` (the default), every command shifted by the band:
    ``V_a = V - v_db tanh(V / v_db)`` [V], ~0 for ``|V| << v_db``, ``V - v_db sign(V)`` beyond (a dead time that
    eats a fixed share of every pulse). ``gap = 1``, commands inside the band give nothing and those beyond pass
    whole (a minimum pulse width, an ESC's minimum throttle): ``V_a = V s(V^2 / v_db^2)`` with the smooth step
    ``s(x) = (1 + tanh(GAP_EDGE (x - 1))) / 2``, half the command at ``|V| = v_db``, 2 % of it at 0.95 ``v_db`` and
    98 % at 1.05 ``v_db``.
    """

    v_db: float = 0.0
    gap: float = 0.0
    name: ClassVar[str] = "voltage_deadband"
    channel: ClassVar[Channel] = "electrical"
    units: ClassVar[dict[str, str]] = {"v_db": "V", "gap": "1"}
    fitted: ClassVar[tuple[str, ...]] = ("v_db",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"v_db": (0.0, 60.0)}  # (a 48 V drive's 8 %: 3.8 V)
    guess: ClassVar[dict[str, float]] = {"v_db": 0.1}
    signature: ClassVar[str] = ("voltage residual with the sign of the command (not of the current); "
                                "no current flows while the command is small")

    def __post_init__(self) -> None:
        if self.gap not in (0.0, 1.0):
            raise ParameterError("voltage_deadband.gap", f"must be 0 (shifted) or 1 (gap), got {self.gap:g}")

    def drive_voltage(self, voltage: Expr, current: Expr, ops: Ops) -> Expr:
        if self.v_db <= 1e-9:
            return voltage
        if self.gap:
            return voltage * 0.5 * (1.0 + ops.tanh(GAP_EDGE * ((voltage / self.v_db) ** 2 - 1.0)))
        return voltage - self.v_db * ops.tanh(voltage / self.v_db)


@dataclass(frozen=True)
class BrushDrop(EffectBase):
    """Brush contact voltage drop: a nearly constant drop against the current (carbon brushes ~0.3-1 V).

    ``V_a = V - v_b tanh(i / i_eps)`` [V].
    """

    v_b: float = 0.0
    i_eps: float = 0.02
    name: ClassVar[str] = "brush_drop"
    channel: ClassVar[Channel] = "electrical"
    units: ClassVar[dict[str, str]] = {"v_b": "V", "i_eps": "A"}
    fitted: ClassVar[tuple[str, ...]] = ("v_b",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"v_b": (0.0, 3.0)}
    guess: ClassVar[dict[str, float]] = {"v_b": 0.1}
    signature: ClassVar[str] = "voltage residual is a step with the sign of the current, same size at every current"

    def __post_init__(self) -> None:
        require_positive("brush_drop.i_eps", self.i_eps)

    def drive_voltage(self, voltage: Expr, current: Expr, ops: Ops) -> Expr:
        return voltage - self.v_b * ops.tanh(current / self.i_eps)


@dataclass(frozen=True)
class CurrentOffset(EffectBase):
    """Current-sensor offset (Hall/shunt amplifier zero error): the sensor reads ``i + i0`` [A]."""

    i0: float = 0.0
    name: ClassVar[str] = "current_offset"
    channel: ClassVar[Channel] = "current-sensor"
    units: ClassVar[dict[str, str]] = {"i0": "A"}
    fitted: ClassVar[tuple[str, ...]] = ("i0",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"i0": (-5.0, 5.0)}
    guess: ClassVar[dict[str, float]] = {"i0": 0.0}
    signature: ClassVar[str] = ("constant current error, also at standstill with zero command; "
                                "torque and voltage residuals both offset by k_t*i0 and R*i0")

    def measured_current(self, current: Expr) -> Expr:
        return current + self.i0



CATALOGUE: dict[str, type[EffectBase]] = {
    cls.name: cls
    for cls in (CoulombFriction, Stribeck, DragAsymmetry, ThrustAsymmetry, ForceOffset, VoltageDeadband,
                BrushDrop, CurrentOffset, InputDelay, ThrustLag, Cogging)
}


def make_effect(name: str, values: Mapping[str, Any] | None = None) -> EffectBase:
    """Effect ``name`` of :data:`CATALOGUE` with parameters ``values`` (SI; omitted ones default)."""
    if name not in CATALOGUE:
        raise ParameterError(f"effects.{name}", f"unknown effect; the catalogue has {sorted(CATALOGUE)}")
    cls = CATALOGUE[name]
    allowed = [f.name for f in fields(cls)]
    if values is not None and not isinstance(values, Mapping):
        raise ParameterError(f"effects.{name}", "must be a mapping of parameter names to numbers")
    values = dict(values or {})
    kwargs: dict[str, float] = {}
    for key, val in values.items():
        if key not in allowed:
            raise ParameterError(f"effects.{name}.{key}", f"unknown parameter; {name} has {allowed}")
        if isinstance(val, bool) or not isinstance(val, int | float) or not math.isfinite(val):
            raise ParameterError(f"effects.{name}.{key}", f"must be a finite number, got {val!r}")
        kwargs[key] = float(val)
    try:
        effect = cls(**kwargs)  # the class's own checks first (they name "<effect>.<key>")
    except ParameterError:
        raise
    except (TypeError, ValueError) as exc:
        raise ParameterError(f"effects.{name}", str(exc)) from None
    for key, val in kwargs.items():
        check_range(name, key, val)
    return effect


def effects_from_mapping(block: Any) -> tuple[EffectBase, ...]:
    """Effects from the ``effects`` block of a parameter file (order kept)."""
    if block is None:
        return ()
    if not isinstance(block, Mapping):
        raise ParameterError("effects", "must be a mapping {effect name: {parameter: value}}")
    return tuple(make_effect(str(k), v) for k, v in block.items())


def load_plant(source: str | Path | Mapping[str, Any]) -> DCMotorPlant:
    """Plant from a preset name, a JSON/YAML parameter file, or a mapping: params + ``effects``."""
    if isinstance(source, str) and source in PRESETS:
        return DCMotorPlant(load_params(source))
    data = dict(source) if isinstance(source, Mapping) else read_mapping(source)
    return DCMotorPlant(params_from_mapping(data), effects_from_mapping(data.get("effects")))


def plant_to_mapping(plant: DCMotorPlant, name: str | None = None, notes: Any = None) -> dict[str, Any]:
    """The parameter-file form of ``plant`` (SI, JSON-ready), readable by :func:`load_plant`."""
    out: dict[str, Any] = {k: float(v) for k, v in plant.params.model_dump().items()}
    out["effects"] = {e.name: effect_parameters(e) for e in plant.effects}
    if name is not None:
        out["name"] = name
    if notes is not None:
        out["notes"] = notes
    return out


def effect_parameters(effect: Effect) -> dict[str, float]:
    """Parameters of a catalogue effect (SI)."""
    if not isinstance(effect, EffectBase):
        raise ParameterError(f"effects.{effect.name}", "is not a catalogue effect; cannot serialise it")
    return effect.parameters()


def measured_current(plant: DCMotorPlant, current: Expr) -> Expr:
    """Current [A] the sensor reports for the true ``current`` (current-sensor effects applied)."""
    for eff in plant.effects:
        current = eff.measured_current(current) if isinstance(eff, EffectBase) else current
    return current


def with_params(plant: DCMotorPlant, params: MotorParams) -> DCMotorPlant:
    """Same effects, other nominal constants."""
    return DCMotorPlant(params, plant.effects)


def stateful(plant: DCMotorPlant) -> list[StatefulBase]:
    """The plant's stateful effects, in state order."""
    return [e for e in plant.effects if effect_states(e) and isinstance(e, StatefulBase)]


def time_scale(plant: DCMotorPlant) -> float:
    """Fastest time constant [s] of the plant: electrical L/R or an effect's states."""
    p = plant.params
    return min([p.L / p.R, *(e.time_scale for e in stateful(plant))])


__all__ = [
    "CATALOGUE", "BrushDrop", "Cogging", "CoulombFriction", "CurrentOffset", "DragAsymmetry", "EffectBase",
    "ForceOffset", "InputDelay", "StatefulBase", "Stribeck", "ThrustAsymmetry", "ThrustLag", "VoltageDeadband",
    "effects_from_mapping", "load_plant", "make_effect", "measured_current", "plant_to_mapping", "stateful",
    "time_scale", "with_params",
]
