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
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, fields
from pathlib import Path
from typing import Any, ClassVar, Literal

import numpy as np
from scipy import signal

from ocp.errors import ParameterError
from ocp.model.params import PRESETS, MotorParams, load_params, params_from_mapping, read_mapping
from ocp.model.plant import DCMotorPlant, Effect, Expr, Ops, effect_states

Channel = Literal["mechanical", "electrical", "thrust", "current-sensor"]


def _sign(w: Expr, eps: float, ops: Ops, sign: float | None) -> Expr:
    """Smooth ``sign(w)`` = ``tanh(w/eps)``; exactly ``sign`` when the phase fixes it."""
    return sign if sign is not None else ops.tanh(w / eps)


def _reverse(w: Expr, eps: float, ops: Ops, sign: float | None) -> Expr:
    """Smooth indicator of reverse rotation (1 for w << 0, 0 for w >> 0)."""
    return 0.5 * (1.0 - _sign(w, eps, ops, sign))


@dataclass(frozen=True)
class EffectBase:
    """Memoryless defaults: no torque, voltage and thrust passed through, current sensed as is."""

    name: ClassVar[str]
    channel: ClassVar[Channel]
    units: ClassVar[dict[str, str]]
    fitted: ClassVar[tuple[str, ...]]
    bounds: ClassVar[dict[str, tuple[float, float]]]
    guess: ClassVar[dict[str, float]]
    signature: ClassVar[str]

    def load_torque(self, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        return 0.0 * omega

    def drive_voltage(self, voltage: Expr, current: Expr, ops: Ops) -> Expr:
        return voltage

    def thrust(self, thrust: Expr, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        return thrust

    def measured_current(self, current: Expr) -> Expr:
        """Current [A] the sensor reports when ``current`` flows."""
        return current

    def parameters(self) -> dict[str, float]:
        """All parameters (SI), by name."""
        return {f.name: float(getattr(self, f.name)) for f in fields(self) if f.name != "name"}

    def describe(self) -> str:
        """One sentence: what the effect is, its fitted magnitude with units, its signature."""
        doc = (type(self).__doc__ or "").strip().splitlines()[0]
        vals = ", ".join(f"{k} = {self.parameters()[k]:.4g} {self.units[k]}" for k in self.fitted)
        return f"{self.name}: {doc} Fitted {vals}. Signature: {self.signature}"



#: accepted range of each effect parameter given in a parameter mapping (SI; inclusive); smoothing widths,
#: time constants and delays are bounded away from 0 (a zero would divide, a tiny one make the plant too
#: stiff to simulate) and from the absurd; any other parameter is bounded by DEFAULT_RANGE
RANGES: dict[str, tuple[float, float]] = {
    "omega_eps": (1e-3, 1e3),  # rad/s
    "stribeck.omega_s": (1e-2, 1e4),  # rad/s
    "input_delay.delay": (1e-5, 1.0),  # s
    "thrust_lag.tau": (1e-5, 100.0),  # s
    "cogging.periods": (1e-2, 1e3),  # 1/rev
    "brush_drop.i_eps": (1e-6, 1e3),  # A
    "voltage_deadband.v_db": (0.0, 1e3),  # V
}
DEFAULT_RANGE = (-1e3, 1e3)


def _check_range(name: str, key: str, value: float) -> None:
    lo, hi = RANGES.get(f"{name}.{key}", RANGES.get(key, DEFAULT_RANGE))
    if not lo <= value <= hi:
        raise ParameterError(f"effects.{name}.{key}", f"must be in [{lo:g}, {hi:g}], got {value:g}")


def _positive(key: str, value: float) -> None:
    if not value > 0:
        raise ParameterError(key, f"must be > 0, got {value}")


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
        return self.tau_c * _sign(omega, self.omega_eps, ops, sign)


@dataclass(frozen=True)
class Stribeck(EffectBase):
    """Stribeck breakaway friction: extra torque near zero speed that vanishes as the film builds.

    ``tau = tau_s exp(-(w/omega_s)^2) tanh(w/omega_eps)`` [N m].
    """

    tau_s: float = 0.0
    omega_s: float = 2.0
    omega_eps: float = 0.5
    name: ClassVar[str] = "stribeck"
    channel: ClassVar[Channel] = "mechanical"
    units: ClassVar[dict[str, str]] = {"tau_s": "N m", "omega_s": "rad/s", "omega_eps": "rad/s"}
    fitted: ClassVar[tuple[str, ...]] = ("tau_s", "omega_s")
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"tau_s": (0.0, 0.1), "omega_s": (0.3, 30.0)}
    guess: ClassVar[dict[str, float]] = {"tau_s": 1e-3, "omega_s": 3.0}
    signature: ClassVar[str] = ("torque residual with the sign of the speed only at low speed (near reversals), "
                                "absent in the high-speed band; the rotor sticks before it reverses")

    def __post_init__(self) -> None:
        _positive("stribeck.omega_s", self.omega_s)

    def load_torque(self, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        r = omega / self.omega_s
        return self.tau_s * ops.exp(-r * r) * _sign(omega, self.omega_eps, ops, sign)


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
        return self.dc_tau * ww * _reverse(omega, self.omega_eps, ops, sign)


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
        return thrust + self.dc_f * ww * _reverse(omega, self.omega_eps, ops, sign)


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


@dataclass(frozen=True)
class VoltageDeadband(EffectBase):
    """Driver dead band (H-bridge dead time, PWM minimum pulse): small commands do not reach the motor.

    ``V_a = V - v_db tanh(V / v_db)`` [V]: ~0 for ``|V| << v_db``, ``V - v_db sign(V)`` beyond.
    """

    v_db: float = 0.0
    name: ClassVar[str] = "voltage_deadband"
    channel: ClassVar[Channel] = "electrical"
    units: ClassVar[dict[str, str]] = {"v_db": "V"}
    fitted: ClassVar[tuple[str, ...]] = ("v_db",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"v_db": (0.0, 3.0)}
    guess: ClassVar[dict[str, float]] = {"v_db": 0.1}
    signature: ClassVar[str] = ("voltage residual with the sign of the command (not of the current); "
                                "no current flows while the command is small")

    def drive_voltage(self, voltage: Expr, current: Expr, ops: Ops) -> Expr:
        if self.v_db <= 1e-9:
            return voltage
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
        _positive("brush_drop.i_eps", self.i_eps)

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


@dataclass(frozen=True)
class _Bound:
    """A stateful effect with its states fixed (what :meth:`StatefulBase.bind` returns)."""

    owner: StatefulBase
    z: tuple[Any, ...]

    @property
    def name(self) -> str:
        return self.owner.name

    def load_torque(self, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        return self.owner.bound_load_torque(self.z, omega, ops)

    def drive_voltage(self, voltage: Expr, current: Expr, ops: Ops) -> Expr:
        return self.owner.bound_drive_voltage(self.z, voltage)

    def thrust(self, thrust: Expr, omega: Expr, ops: Ops, sign: float | None) -> Expr:
        return self.owner.bound_thrust(self.z, thrust)


@dataclass(frozen=True)
class StatefulBase(EffectBase):
    """Defaults of a stateful effect: bound hooks pass everything through."""

    states: ClassVar[tuple[str, ...]]

    def bind(self, z: Sequence[Expr]) -> Effect:
        return _Bound(owner=self, z=tuple(z))

    def bound_load_torque(self, z: Sequence[Expr], omega: Expr, ops: Ops) -> Expr:
        return 0.0 * omega

    def bound_drive_voltage(self, z: Sequence[Expr], voltage: Expr) -> Expr:
        return voltage

    def bound_thrust(self, z: Sequence[Expr], thrust: Expr) -> Expr:
        return thrust

    @property
    def time_scale(self) -> float:
        """Fastest time constant [s] of the effect's states (sets the integration step)."""
        return math.inf

    def observe(self, t: np.ndarray, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
                theta: np.ndarray | None) -> np.ndarray:
        """States (n_states, N) reconstructed from measured signals (N,) on the uniform grid ``t``."""
        raise NotImplementedError

    def steady(self, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
               theta: np.ndarray | None) -> np.ndarray:
        """States (n_states, N) at rest at each operating point (steady-state sweeps)."""
        raise NotImplementedError


def _lti_states(a: np.ndarray, b: np.ndarray, u: np.ndarray, dt: float) -> np.ndarray:
    """States (n, N) of ``z' = a z + b u`` under zero-order-held ``u`` (N,), starting at steady state.

    Exact ZOH discretisation, each state filtered by its own transfer function (``lfilter``, C speed).
    """
    n = a.shape[0]
    ad, bd, *_ = signal.cont2discrete((a, b.reshape(n, 1), np.eye(n), np.zeros((n, 1))), dt, method="zoh")
    z = np.empty((n, u.size))
    for j in range(n):
        num, den = signal.ss2tf(ad, bd, np.eye(n)[j:j + 1], np.zeros((1, 1)))
        num = np.atleast_1d(np.squeeze(num))
        zi = signal.lfilter_zi(num, den) * u[0]
        z[j] = signal.lfilter(num, den, u, zi=zi)[0]
    return z


@dataclass(frozen=True)
class InputDelay(StatefulBase):
    """Transport delay between the logged command and the armature (driver latency, PWM update, bus).

    ``V_a(t) = V(t - delay)``, realised as the 2nd-order Pade approximant
    ``(1 - sd/2 + (sd)^2/12) / (1 + sd/2 + (sd)^2/12)`` (states z1, z2; exact at low frequency,
    phase error < 1 deg up to ``f = 0.1/delay``).
    """

    delay: float = 1e-3
    name: ClassVar[str] = "input_delay"
    states: ClassVar[tuple[str, ...]] = ("z1", "z2")
    channel: ClassVar[Channel] = "electrical"
    units: ClassVar[dict[str, str]] = {"delay": "s"}
    fitted: ClassVar[tuple[str, ...]] = ("delay",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"delay": (2e-4, 0.05)}
    guess: ClassVar[dict[str, float]] = {"delay": 2e-3}
    signature: ClassVar[str] = ("current residual correlated with the voltage *rate*: the measured current "
                                "responds later than the model; cross-correlation peaks at a positive lag")

    def __post_init__(self) -> None:
        _positive("input_delay.delay", self.delay)

    def _ab(self) -> tuple[np.ndarray, np.ndarray]:
        d = self.delay
        return np.array([[0.0, 1.0], [-12.0 / d**2, -6.0 / d]]), np.array([0.0, 1.0])

    def state_rhs(self, z: Sequence[Expr], omega: Expr, voltage: Expr, thrust: Expr, ops: Ops) -> list[Expr]:
        d = self.delay
        return [z[1], -12.0 / d**2 * z[0] - 6.0 / d * z[1] + voltage]

    def bound_drive_voltage(self, z: Sequence[Expr], voltage: Expr) -> Expr:
        # Pade(2): H(s) = 1 - (12/d) s / (s^2 + 6 s/d + 12/d^2)
        return voltage - 12.0 / self.delay * z[1]

    @property
    def time_scale(self) -> float:
        return self.delay / math.sqrt(12.0)

    def observe(self, t: np.ndarray, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
                theta: np.ndarray | None) -> np.ndarray:
        a, b = self._ab()
        return _lti_states(a, b, voltage, float(np.median(np.diff(t))))

    def steady(self, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
               theta: np.ndarray | None) -> np.ndarray:
        return np.vstack([voltage * self.delay**2 / 12.0, np.zeros_like(voltage)])


@dataclass(frozen=True)
class ThrustLag(StatefulBase):
    """Inflow (wake) dynamics: the thrust follows the quasi-static ``c_f w|w|`` with a first-order lag.

    ``tau F' = F_static - F`` (state ``F`` [N], ``tau`` [s]).
    """

    tau: float = 0.02
    name: ClassVar[str] = "thrust_lag"
    states: ClassVar[tuple[str, ...]] = ("thrust",)
    channel: ClassVar[Channel] = "thrust"
    units: ClassVar[dict[str, str]] = {"tau": "s"}
    fitted: ClassVar[tuple[str, ...]] = ("tau",)
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"tau": (1e-3, 1.0)}
    guess: ClassVar[dict[str, float]] = {"tau": 0.02}
    signature: ClassVar[str] = ("thrust residual proportional to -dF/dt: measured thrust lags the speed, "
                                "largest where thrust changes fast, zero in holds")

    def __post_init__(self) -> None:
        _positive("thrust_lag.tau", self.tau)

    def state_rhs(self, z: Sequence[Expr], omega: Expr, voltage: Expr, thrust: Expr, ops: Ops) -> list[Expr]:
        return [(thrust - z[0]) / self.tau]

    def bound_thrust(self, z: Sequence[Expr], thrust: Expr) -> Expr:
        return z[0]

    @property
    def time_scale(self) -> float:
        return self.tau

    def observe(self, t: np.ndarray, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
                theta: np.ndarray | None) -> np.ndarray:
        dt = float(np.median(np.diff(t)))
        mid = np.concatenate([[thrust[0]], 0.5 * (thrust[1:] + thrust[:-1])])
        return _lti_states(np.array([[-1.0 / self.tau]]), np.array([1.0 / self.tau]), np.roll(mid, -1), dt)

    def steady(self, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
               theta: np.ndarray | None) -> np.ndarray:
        return np.asarray(thrust, float).reshape(1, -1)


@dataclass(frozen=True)
class Cogging(StatefulBase):
    """Cogging / angle-periodic torque ripple (magnet-slot attraction, commutator, shaft eccentricity).

    ``tau = tau_sin sin(n theta) + tau_cos cos(n theta)`` [N m], ``n`` periods per revolution; the
    rotor angle ``theta`` [rad] becomes a state (``theta' = w``).
    """

    tau_sin: float = 0.0
    tau_cos: float = 0.0
    periods: float = 2.0
    name: ClassVar[str] = "cogging"
    states: ClassVar[tuple[str, ...]] = ("theta",)
    channel: ClassVar[Channel] = "mechanical"
    units: ClassVar[dict[str, str]] = {"tau_sin": "N m", "tau_cos": "N m", "periods": "1/rev"}
    fitted: ClassVar[tuple[str, ...]] = ("tau_sin", "tau_cos")
    bounds: ClassVar[dict[str, tuple[float, float]]] = {"tau_sin": (-0.1, 0.1), "tau_cos": (-0.1, 0.1)}
    guess: ClassVar[dict[str, float]] = {"tau_sin": 0.0, "tau_cos": 0.0}
    signature: ClassVar[str] = ("torque residual periodic in the rotor angle (n per revolution), "
                                "largest at low speed; binned against angle it draws a sine")

    def __post_init__(self) -> None:
        _positive("cogging.periods", self.periods)

    def state_rhs(self, z: Sequence[Expr], omega: Expr, voltage: Expr, thrust: Expr, ops: Ops) -> list[Expr]:
        return [omega]

    def bound_load_torque(self, z: Sequence[Expr], omega: Expr, ops: Ops) -> Expr:
        return self.tau_sin * ops.sin(self.periods * z[0]) + self.tau_cos * ops.cos(self.periods * z[0])

    def observe(self, t: np.ndarray, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
                theta: np.ndarray | None) -> np.ndarray:
        if theta is not None:
            return theta.reshape(1, -1)
        th = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(t))])
        return th.reshape(1, -1)

    def steady(self, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
               theta: np.ndarray | None) -> np.ndarray:
        return (np.zeros_like(omega) if theta is None else theta).reshape(1, -1)


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
        _check_range(name, key, val)
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
