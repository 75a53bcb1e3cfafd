"""One plant abstraction for the simulator, the optimiser and the model fitter.

Two plants share one interface (:class:`Plant`):

* :class:`DCMotorPlant` -- states ``x = (omega [rad/s], current [A])``, input ``voltage [V]``
  (paper eqs. dc_mechanical, dc_electrical), optionally extended by effects (see :class:`Effect`).
* :class:`TorquePlant` -- the normalised torque-input channel, state ``x = (omega,)``, input
  ``u = tau_m / J [rad/s^2]`` (paper eq. omega_dyn), for drives that control torque/current.

Besides its dynamics a plant answers what its callers would otherwise branch on: its nominal static
inverse, its input limit and bounded states under a mission's :class:`DriveBounds`, the limit ratios of a
response, the channels an answer reports (for the torque channel with the DC motor's equivalent current
and voltage). Which plant a mission gets is decided in one place, :func:`ocp.model.factory.make_plant`.

The right-hand sides are written once and evaluated on numpy arrays (simulation, fitting) or on
CasADi symbols (collocation) through an :class:`Ops` backend. Inside an optimiser phase the sign
of ``omega`` is fixed; passing ``sign=+1/-1`` replaces ``w|w|`` by the smooth ``sign*w^2``.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, Protocol

import casadi as ca
import numpy as np

from ocp.model.params import MotorParams

Expr = Any  # float, numpy array or casadi SX/MX


@dataclass(frozen=True)
class Ops:
    """Elementary functions of one backend (numpy or CasADi)."""

    abs: Callable[[Expr], Expr]
    sqrt: Callable[[Expr], Expr]
    tanh: Callable[[Expr], Expr]
    exp: Callable[[Expr], Expr]
    sign: Callable[[Expr], Expr]
    sin: Callable[[Expr], Expr] = np.sin
    cos: Callable[[Expr], Expr] = np.cos


NUMPY = Ops(abs=np.abs, sqrt=np.sqrt, tanh=np.tanh, exp=np.exp, sign=np.sign, sin=np.sin, cos=np.cos)
CASADI = Ops(abs=ca.fabs, sqrt=ca.sqrt, tanh=ca.tanh, exp=ca.exp, sign=ca.sign, sin=ca.sin, cos=ca.cos)


def signed_square(w: Expr, ops: Ops = NUMPY, sign: Expr | None = None) -> Expr:
    """``w|w|``; with a known ``sign`` of ``w`` the smooth ``sign * w**2``."""
    return sign * w * w if sign is not None else w * ops.abs(w)


# eq:thrust_model  F = c_f w|w|
def thrust_from_speed(omega: Expr, c_f: float, ops: Ops = NUMPY, sign: Expr | None = None) -> Expr:
    """Static thrust map: speed [rad/s] -> thrust [N]."""
    return c_f * signed_square(omega, ops, sign)


def speed_from_thrust(thrust: np.ndarray | float, c_f: float) -> np.ndarray:
    """Inverse static map ``omega = sign(F) sqrt(|F|/c_f)`` [rad/s] (Fig. 1 of the paper)."""
    f = np.asarray(thrust, dtype=float)
    return np.sign(f) * np.sqrt(np.abs(f) / c_f)


class Effect(Protocol):
    """A named physical effect that extends :class:`DCMotorPlant` (catalogue: ``ocp.model.effects``).

    Each hook returns an expression in the given backend; an effect that does not act on a channel
    returns its input unchanged (or 0 for ``load_torque``).
    """

    @property
    def name(self) -> str:
        """Catalogue name of the effect."""
        ...

    def load_torque(self, omega: Expr, ops: Ops, sign: Expr | None) -> Expr:
        """Extra torque opposing motion [N m], added to the drag and viscous terms."""
        ...

    def drive_voltage(self, voltage: Expr, current: Expr, ops: Ops) -> Expr:
        """Voltage [V] that reaches the armature when ``voltage`` is commanded."""
        ...

    def thrust(self, thrust: Expr, omega: Expr, ops: Ops, sign: Expr | None) -> Expr:
        """Measured thrust [N] given the ideal ``thrust`` of eq. thrust_model."""
        ...


class StatefulEffect(Effect, Protocol):
    """An effect with internal states ``z`` (e.g. an input delay, inflow lag, the rotor angle).

    Its states are appended to the plant state after ``(omega, current)``, in effect order, named
    ``"<effect name>.<state>"``. Inside :meth:`DCMotorPlant.rhs` the effect is first bound to its
    states (:meth:`bind` returns a plain :class:`Effect` whose hooks see ``z``), and its state
    derivative is computed from the signals that reach it in the chain: ``voltage`` is the command
    after the preceding effects' ``drive_voltage``, ``thrust`` the thrust after the preceding
    effects' ``thrust``.
    """

    states: tuple[str, ...]

    def bind(self, z: Sequence[Expr]) -> Effect:
        """The effect's hooks with its states fixed to ``z``."""
        ...

    def state_rhs(self, z: Sequence[Expr], omega: Expr, voltage: Expr, thrust: Expr, ops: Ops) -> list[Expr]:
        """Time derivative of ``z`` (same layout)."""
        ...


def effect_states(effect: Effect) -> tuple[str, ...]:
    """Names of an effect's internal states (``()`` for a plain, memoryless effect)."""
    states = getattr(effect, "states", ())
    return tuple(states)


class Plant(Protocol):
    """What the simulator, the optimiser and the fitter need from a plant."""

    @property
    def state_names(self) -> tuple[str, ...]: ...

    @property
    def input_name(self) -> str: ...

    def rhs(self, x: Sequence[Expr], u: Expr, ops: Ops = NUMPY, sign: Expr | None = None) -> list[Expr]:
        """Time derivative of the state (same layout as ``x``)."""
        ...

    def thrust(self, x: Sequence[Expr], ops: Ops = NUMPY, sign: Expr | None = None) -> Expr:
        """Thrust [N] produced in state ``x``."""
        ...


@dataclass(frozen=True)
class DriveBounds:
    """A mission's actuator limits, resolved (magnitudes, SI).

    Attributes:
        voltage: armature voltage [V]; current: armature current [A]
        torque: torque of the torque channel [N m] (resolved: the mission's or its default)
        speed: rotor speed [rad/s], None = unconstrained
    """

    voltage: float
    current: float
    torque: float
    speed: float | None = None


class ReferenceLike(Protocol):
    """What :meth:`DrivenPlant.feedforward` reads of a closed-form reference
    (:class:`ocp.reference.trajectory.Reference`): arrays (M,) of speed [rad/s], its derivative [rad/s^2],
    current [A] and voltage [V] of the nominal motor."""

    @property
    def omega(self) -> np.ndarray: ...

    @property
    def omega_dot(self) -> np.ndarray: ...

    @property
    def current(self) -> np.ndarray: ...

    @property
    def voltage(self) -> np.ndarray: ...


class DrivenPlant(Plant, Protocol):
    """A plant the optimiser, the fallback and the verification drive under a mission's limits."""

    #: thrust exponent g imposed at a reversal when the input must be continuous (6: current and voltage both
    #: vanish there, omega ~ s^3; the torque channel has no current state to make vanish: 2)
    smooth_reversal_order: ClassVar[int]

    @property
    def voltage_driven(self) -> bool:
        """Whether the input is the armature voltage (the analytic designs and the Section V loop need it)."""
        ...

    @property
    def is_nominal(self) -> bool:
        """No effects: :meth:`static_inverse` is the exact equilibrium."""
        ...

    def voltage_plant(self) -> DCMotorPlant | None:
        """This plant as a voltage-input DC motor (what a voltage loop such as Section V's drives), or None."""
        ...

    def static_inverse(self, omega: Any) -> tuple[list[np.ndarray], np.ndarray]:
        """Nominal states (omega and, for the DC motor, the current) and input holding ``omega`` [rad/s]
        constant (effects left out), each shaped like ``omega``."""
        ...

    def feedforward(self, ref: ReferenceLike) -> tuple[list[np.ndarray], np.ndarray]:
        """Nominal states and input along a closed-form reference (exact for the nominal plant), shapes (M,)."""
        ...

    def input_limit(self, bounds: DriveBounds) -> float:
        """Largest |input| [V or rad/s^2]."""
        ...

    def state_limits(self, bounds: DriveBounds) -> dict[int, float]:
        """Largest |state| [SI] by state index, for the states the limits bound (the speed apart)."""
        ...

    def torque_limit(self, bounds: DriveBounds) -> float | None:
        """Torque bound [N m] the analytic designs must respect; None when current and voltage bound the plant."""
        ...

    def channels(self, x: np.ndarray, u: np.ndarray) -> dict[str, np.ndarray]:
        """Reported drive channels of states ``x`` (n_states, K) under input ``u`` (K,): current [A] and
        voltage [V] (for the torque channel first its normalised torque [rad/s^2], then the DC equivalents)."""
        ...

    def limit_ratios(self, channels: Mapping[str, Any], bounds: DriveBounds) -> dict[str, Any]:
        """|channel| / limit for each limit of the drive (``limits.<name>`` keys) from :meth:`channels`' values."""
        ...

    def peak_report(self, peak: Callable[[str], float], bounds: DriveBounds,
                    tolerance: float) -> tuple[dict[str, Any], bool]:
        """Extra peak fields [SI] of a verification from ``peak(channel)`` (the largest |value|), and whether the
        drive limits hold within ``tolerance`` (relative, e.g. 1.001)."""
        ...


@dataclass(frozen=True)
class DCMotorPlant:
    """Brushed DC motor driving a bidirectional propeller; input V.

    State ``(omega [rad/s], current [A])``, followed by the internal states of stateful effects
    (:class:`StatefulEffect`), in effect order; :attr:`state_names` lists them all.
    """

    params: MotorParams
    effects: tuple[Effect, ...] = field(default=())
    input_name: str = "voltage"

    @property
    def state_names(self) -> tuple[str, ...]:
        names = ["omega", "current"]
        for eff in self.effects:
            names += [f"{eff.name}.{s}" for s in effect_states(eff)]
        return tuple(names)

    def _bound(self, x: Sequence[Expr]) -> list[tuple[Effect, StatefulEffect | None, list[Expr]]]:
        """(effect with states bound, the stateful effect or None, its states) per effect."""
        out: list[tuple[Effect, StatefulEffect | None, list[Expr]]] = []
        k = 2
        for eff in self.effects:
            n = len(effect_states(eff))
            if n == 0:
                out.append((eff, None, []))
                continue
            z = [x[m] for m in range(k, k + n)]
            stateful: StatefulEffect = eff  # type: ignore[assignment]
            out.append((stateful.bind(z), stateful, z))
            k += n
        return out

    def _thrust_chain(self, w: Expr, bound: Sequence[tuple[Effect, Any, Any]], ops: Ops,
                      sign: Expr | None) -> tuple[Expr, list[Expr]]:
        """Thrust after all effects and the thrust reaching each effect."""
        f = thrust_from_speed(w, self.params.c_f, ops, sign)
        inputs = []
        for b, _, _ in bound:
            inputs.append(f)
            f = b.thrust(f, w, ops, sign)
        return f, inputs

    def rhs(self, x: Sequence[Expr], u: Expr, ops: Ops = NUMPY, sign: Expr | None = None) -> list[Expr]:
        p = self.params
        w, i = x[0], x[1]
        load = p.B * w + p.c_tau * signed_square(w, ops, sign)
        v = u
        bound = self._bound(x)
        extra: list[Expr] = []
        f_in: list[Expr] = []
        if any(s is not None for _, s, _ in bound):
            f_in = self._thrust_chain(w, bound, ops, sign)[1]
        for j, (eff, stateful, z) in enumerate(bound):
            if stateful is not None:
                extra += stateful.state_rhs(z, w, v, f_in[j], ops)
            load = load + eff.load_torque(w, ops, sign)
            v = eff.drive_voltage(v, i, ops)
        # eq:dc_mechanical  J w' = k_t i - B w - c_tau w|w|
        dw = (p.k_t * i - load) / p.J
        # eq:dc_electrical  L i' = V - R i - k_e w
        di = (v - p.R * i - p.k_e * w) / p.L
        return [dw, di, *extra]

    def thrust(self, x: Sequence[Expr], ops: Ops = NUMPY, sign: Expr | None = None) -> Expr:
        return self._thrust_chain(x[0], self._bound(x), ops, sign)[0]

    def steady_state(self, omega: float) -> tuple[float, float]:
        """(current [A], voltage [V]) that hold ``omega`` [rad/s] constant (no effects)."""
        p = self.params
        # eq:dc_mechanical at rest  k_t i = B w + c_tau w|w|
        i = (p.B * omega + p.c_tau * omega * abs(omega)) / p.k_t
        # eq:dc_electrical at rest  V = R i + k_e w
        return i, p.R * i + p.k_e * omega

    smooth_reversal_order: ClassVar[int] = 6

    @property
    def voltage_driven(self) -> bool:
        return True

    @property
    def is_nominal(self) -> bool:
        return not self.effects

    def voltage_plant(self) -> DCMotorPlant | None:
        return self

    def static_inverse(self, omega: Any) -> tuple[list[np.ndarray], np.ndarray]:
        w = np.asarray(omega, float)
        i, v = self.steady_state(w)  # type: ignore[arg-type]  # vectorised: abs() of an array
        return [w, np.asarray(i)], np.asarray(v)

    def feedforward(self, ref: ReferenceLike) -> tuple[list[np.ndarray], np.ndarray]:
        return [ref.omega, ref.current], ref.voltage

    def input_limit(self, bounds: DriveBounds) -> float:
        return bounds.voltage

    def state_limits(self, bounds: DriveBounds) -> dict[int, float]:
        return {1: bounds.current}

    def torque_limit(self, bounds: DriveBounds) -> float | None:
        return None

    def channels(self, x: np.ndarray, u: np.ndarray) -> dict[str, np.ndarray]:
        return {"current": x[1], "voltage": u}

    def limit_ratios(self, channels: Mapping[str, Any], bounds: DriveBounds) -> dict[str, Any]:
        return {"limits.current": np.abs(channels["current"]) / bounds.current,
                "limits.voltage": np.abs(channels["voltage"]) / bounds.voltage}

    def peak_report(self, peak: Callable[[str], float], bounds: DriveBounds,
                    tolerance: float) -> tuple[dict[str, Any], bool]:
        return {}, peak("current") <= bounds.current * tolerance and peak("voltage") <= bounds.voltage * tolerance


@dataclass(frozen=True)
class TorquePlant:
    """Normalised torque-input channel (paper eq. omega_dyn): ``omega' = u - k omega|omega|``.

    Attributes:
        k: normalised drag c_tau/J [1/rad]
        c_f: thrust coefficient [N s^2/rad^2] used by :meth:`thrust`
        params: the motor behind the channel (its J turns the torque limit into the input limit, its R, k_e,
            k_t give the DC-equivalent current and voltage); not part of the dynamics' identity
    """

    k: float
    c_f: float = 1.0
    state_names: tuple[str, ...] = ("omega",)
    input_name: str = "torque"
    params: MotorParams | None = field(default=None, repr=False, compare=False)
    smooth_reversal_order: ClassVar[int] = 2

    @classmethod
    def from_params(cls, params: MotorParams) -> TorquePlant:
        return cls(k=params.k, c_f=params.c_f, params=params)

    def _motor(self) -> MotorParams:
        if self.params is None:
            raise ValueError("this torque channel has no motor parameters (build it with TorquePlant.from_params)")
        return self.params

    @property
    def voltage_driven(self) -> bool:
        return False

    @property
    def is_nominal(self) -> bool:
        return True

    def voltage_plant(self) -> DCMotorPlant | None:
        return None

    def static_inverse(self, omega: Any) -> tuple[list[np.ndarray], np.ndarray]:
        w = np.asarray(omega, float)
        # eq:omega_dyn at rest  u = k w|w|
        return [w], self.k * w * np.abs(w)

    def feedforward(self, ref: ReferenceLike) -> tuple[list[np.ndarray], np.ndarray]:
        # eq:omega_dyn  u = w' + k w|w|
        return [ref.omega], ref.omega_dot + self.k * ref.omega * np.abs(ref.omega)

    def input_limit(self, bounds: DriveBounds) -> float:
        return bounds.torque / self._motor().J

    def state_limits(self, bounds: DriveBounds) -> dict[int, float]:
        return {}

    def torque_limit(self, bounds: DriveBounds) -> float | None:
        return bounds.torque

    def dc_equivalent(self, w: np.ndarray, u: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Current [A] and voltage [V] a DC motor would need for speed ``w`` under the normalised torque ``u``
        (tau = J u covers inertia and drag; the viscous B w adds)."""
        p = self._motor()
        i = p.J * u / p.k_t + p.B * w / p.k_t
        return i, p.R * i + p.k_e * w

    def channels(self, x: np.ndarray, u: np.ndarray) -> dict[str, np.ndarray]:
        i, v = self.dc_equivalent(x[0], u)
        return {"torque": u, "current": i, "voltage": v}

    def limit_ratios(self, channels: Mapping[str, Any], bounds: DriveBounds) -> dict[str, Any]:
        return {"limits.torque": np.abs(channels["torque"]) * self._motor().J / bounds.torque}

    def peak_report(self, peak: Callable[[str], float], bounds: DriveBounds,
                    tolerance: float) -> tuple[dict[str, Any], bool]:
        tau_max = peak("torque") * self._motor().J  # the drive owns i and V (reported as the DC equivalent)
        return {"max_abs_torque": tau_max, "torque_margin": bounds.torque - tau_max}, \
            tau_max <= bounds.torque * tolerance

    def rhs(self, x: Sequence[Expr], u: Expr, ops: Ops = NUMPY, sign: Expr | None = None) -> list[Expr]:
        w = x[0]
        # eq:omega_dyn  w' = u - k w|w|
        return [u - self.k * signed_square(w, ops, sign)]

    def thrust(self, x: Sequence[Expr], ops: Ops = NUMPY, sign: Expr | None = None) -> Expr:
        return thrust_from_speed(x[0], self.c_f, ops, sign)
