"""Effects with internal states (an input delay, a thrust lag, cogging over the rotor angle).

Their states extend :class:`ocp.model.plant.DCMotorPlant`'s after ``(omega, current)`` (see
:class:`~ocp.model.plant.StatefulEffect`). Part of the catalogue :mod:`ocp.model.effects`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from ocp.model.effect_base import Channel, EffectBase, require_positive
from ocp.model.plant import NUMPY, Effect, Expr, Ops

#: angles per period a ripple's peaks are read on (:meth:`Cogging.breakaway`; under 1e-4 relative error up to its 3rd
#: harmonic)
RIPPLE_GRID = 720


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
    #: whether a log measures the states (the rotor angle, logged or integrated from the speed): a free run reads
    #: them from the log at every sample instead of simulating them (:func:`ocp.identify.predict.free_run`)
    measured: ClassVar[bool] = False

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

    Exact ZOH discretisation, each state filtered by its own transfer function (:mod:`ocp.filters`, compiled).
    """
    from ocp.filters import iir, zoh_transfer  # (scipy.linalg: only identification reaches this; workers need not)

    return np.vstack([iir(num, den, u, start=u[0]) for num, den in zoh_transfer(a, b, dt)])


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
        require_positive("input_delay.delay", self.delay)

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
        require_positive("thrust_lag.tau", self.tau)

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

    ``tau = sum_h tau_sin_h sin(h n theta) + tau_cos_h cos(h n theta)`` [N m] over the harmonics h = 1, 2, 3
    (``tau_sin``/``tau_cos``, ``tau_sin2``/``tau_cos2``, ``tau_sin3``/``tau_cos3``), ``n`` periods per revolution; the
    rotor angle ``theta`` [rad] becomes a state (``theta' = w``; a free run reads it from the log, :attr:`measured`).
    A detent torque is periodic, not a sine: its shape (peaked or flat-topped where a magnet edge passes a slot) puts
    power at multiples of its count; the first two are modelled, higher ones are left in the residual.
    """

    tau_sin: float = 0.0
    tau_cos: float = 0.0
    periods: float = 2.0
    tau_sin2: float = 0.0
    tau_cos2: float = 0.0
    tau_sin3: float = 0.0
    tau_cos3: float = 0.0
    name: ClassVar[str] = "cogging"
    states: ClassVar[tuple[str, ...]] = ("theta",)
    measured: ClassVar[bool] = True
    channel: ClassVar[Channel] = "mechanical"
    fitted: ClassVar[tuple[str, ...]] = ("tau_sin", "tau_cos", "tau_sin2", "tau_cos2", "tau_sin3", "tau_cos3")
    units: ClassVar[dict[str, str]] = {**{k: "N m" for k in fitted}, "periods": "1/rev"}
    bounds: ClassVar[dict[str, tuple[float, float]]] = {k: (-0.1, 0.1) for k in fitted}
    guess: ClassVar[dict[str, float]] = {k: 0.0 for k in fitted}
    signature: ClassVar[str] = ("torque residual periodic in the rotor angle (n per revolution), "
                                "largest at low speed; binned against angle it draws a sine, or a periodic shape "
                                "with harmonics")

    def __post_init__(self) -> None:
        require_positive("cogging.periods", self.periods)

    def state_rhs(self, z: Sequence[Expr], omega: Expr, voltage: Expr, thrust: Expr, ops: Ops) -> list[Expr]:
        return [omega]

    def bound_load_torque(self, z: Sequence[Expr], omega: Expr, ops: Ops) -> Expr:
        n = self.periods * z[0]
        return sum((s * ops.sin(h * n) + c * ops.cos(h * n) for h, s, c in self.harmonics()), 0.0 * z[0])

    def breakaway(self) -> float:
        """The torque [N m] the ripple holds a rotor at rest against: the smaller of its peaks in the two directions
        (eq. cogging over one period, on :data:`RIPPLE_GRID` angles): a drive weaker than that leaves the rotor a
        stable rest point in a well (the tilted washboard's condition), whichever way it turns."""
        theta = np.linspace(0.0, 2.0 * np.pi, RIPPLE_GRID, endpoint=False) / self.periods  # [rad] one period
        tau = np.asarray(self.bound_load_torque([theta], theta, NUMPY), float)
        return float(min(np.max(tau), -np.min(tau)))

    def describe(self) -> str:
        """The effect's sentence (:meth:`EffectBase.describe`) with its count and the amplitude of each harmonic."""
        amp = [(h, math.hypot(s, c)) for h, s, c in self.harmonics()]
        return (super().describe() + f"; {self.periods:g} periods per revolution, amplitude {amp[0][1]:.3g} N m"
                + "".join(f"; its {h}x harmonic {a:.3g} N m" for h, a in amp[1:]) + ".")

    def harmonics(self) -> list[tuple[int, float, float]]:
        """The fundamental (h = 1) and the harmonics with a non-zero amplitude: (h, sine [N m], cosine [N m])."""
        out = [(1, self.tau_sin, self.tau_cos), (2, self.tau_sin2, self.tau_cos2), (3, self.tau_sin3, self.tau_cos3)]
        return [x for x in out if x[0] == 1 or x[1] or x[2]]

    def observe(self, t: np.ndarray, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
                theta: np.ndarray | None) -> np.ndarray:
        if theta is not None:
            return theta.reshape(1, -1)
        th = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(t))])
        return th.reshape(1, -1)

    def steady(self, omega: np.ndarray, voltage: np.ndarray, thrust: np.ndarray,
               theta: np.ndarray | None) -> np.ndarray:
        return (np.zeros_like(omega) if theta is None else theta).reshape(1, -1)
