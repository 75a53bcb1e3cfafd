"""What every catalogue effect shares (:mod:`ocp.model.effects`): the memoryless defaults, smoothed signs and
the accepted parameter ranges."""

from __future__ import annotations

from dataclasses import dataclass, fields
from typing import ClassVar, Literal

from ocp.errors import ParameterError
from ocp.model.plant import Expr, Ops

Channel = Literal["mechanical", "electrical", "thrust", "current-sensor"]


def smooth_sign(w: Expr, eps: float, ops: Ops, sign: float | None) -> Expr:
    """Smooth ``sign(w)`` = ``tanh(w/eps)``; exactly ``sign`` when the phase fixes it."""
    return sign if sign is not None else ops.tanh(w / eps)


def reverse_weight(w: Expr, eps: float, ops: Ops, sign: float | None) -> Expr:
    """Smooth indicator of reverse rotation (1 for w << 0, 0 for w >> 0)."""
    return 0.5 * (1.0 - smooth_sign(w, eps, ops, sign))


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

    def breakaway(self) -> float:
        """The torque [N m] this effect holds a rotor at rest against (dry friction: any torque up to it; an angle
        ripple: in one of its wells); 0: none."""
        return 0.0

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
    "stribeck.delta": (0.25, 4.0),  # 1 (the decay's exponent)
    "input_delay.delay": (1e-5, 1.0),  # s
    "thrust_lag.tau": (1e-5, 100.0),  # s
    "cogging.periods": (1e-2, 1e3),  # 1/rev
    "brush_drop.i_eps": (1e-6, 1e3),  # A
    "voltage_deadband.v_db": (0.0, 1e3),  # V
}
DEFAULT_RANGE = (-1e3, 1e3)


def check_range(name: str, key: str, value: float) -> None:
    lo, hi = RANGES.get(f"{name}.{key}", RANGES.get(key, DEFAULT_RANGE))
    if not lo <= value <= hi:
        raise ParameterError(f"effects.{name}.{key}", f"must be in [{lo:g}, {hi:g}], got {value:g}")


def require_positive(key: str, value: float) -> None:
    if not value > 0:
        raise ParameterError(key, f"must be > 0, got {value}")

