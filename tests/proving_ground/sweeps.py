"""Steady-state sweeps from the proving ground's rig: one row per operating point, as a bench exports them.

The rig (:mod:`.physics`: its constants, friction, drag, thrust and drive formulas) is held at a commanded voltage
until it settles; each row is the settled point, averaged over the hold: the command [V], the current the sensor
reads [A], the speed [rad/s] and the load cell's thrust [N], each with the noise left after averaging. The settled
point solves, independently of ``ocp``:

* armature at rest (di/dt = 0): ``V_a - v_b sign(i) = R i + k w``, ``V_a`` the drive's output (dead zone applied),
  the brush drop set-valued at ``i = 0`` (the current is the shrinkage of ``V_a - k w`` by ``v_b``, over ``R``);
* rotor at rest (dw/dt = 0): ``k i = tau(w)`` with :func:`.physics.load_torque` (the ripple averages out over a
  turn: drawn without one); where the motor's torque at standstill is within the dry friction, the rotor stays at 0.

Only what a sweep can show is drawn: no time effects (delays, lags, ripples), no ``J`` or ``L`` errors. A label is
kept only where the sweep shows it (:func:`visible`: the rows with and without it differ by
:data:`.cases.VISIBLE` noise levels in some channel, RMS over the rows, as the time-series proving ground asks).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from tests.proving_ground.cases import TOLERANCE, VISIBLE, Drawn, _nominal, draw_effect, draw_motor
from tests.proving_ground.physics import Truth, drive_voltage, load_torque, quasi_static_thrust

#: effects a steady sweep can show (no time, no angle)
SWEEP_EFFECTS = ("coulomb_friction", "stribeck", "drag_asymmetry", "thrust_asymmetry", "force_offset",
                 "voltage_deadband", "brush_drop", "current_offset")
#: constants a steady sweep can show (no J, no L)
SWEEP_CONSTANTS = ("B", "c_tau", "c_f", "k", "R")
#: through an ESC the armature's voltage and current are not logged, and the supply power's scale is the drive's
#: efficiency: what the thrust map and the power balance's shape show
ESC_EFFECTS = ("coulomb_friction", "stribeck", "drag_asymmetry", "thrust_asymmetry", "force_offset")
ESC_CONSTANTS = ("c_f",)


@dataclass
class Sweep(Drawn):
    """One sweep: ``columns`` voltage [V], current [A], omega [rad/s], thrust [N], (P,) each (no logger, timing or
    excitation: settled rows)."""


def settle(t: Truth, v_cmd: float) -> tuple[float, float]:
    """The settled ``(w [rad/s], i [A])`` of rig ``t`` under the command ``v_cmd`` [V] (module doc). Found by
    bisection on the torque balance, which falls with speed (back-EMF) faster than Stribeck's decay can rise."""
    tau, vb, v_a = load_torque(t), t.e("brush_drop", "v_b"), drive_voltage(t, v_cmd)

    def current(w: float) -> float:
        u = v_a - t.k * w
        return math.copysign(max(abs(u) - vb, 0.0), u) / t.R

    dry = t.e("coulomb_friction", "tau_c") + t.e("stribeck", "tau_s")
    if abs(t.k * current(0.0)) <= dry:  # the motor's standstill torque is within the friction: at rest
        return 0.0, current(0.0)

    def balance(w: float) -> float:
        return t.k * current(w) - tau(w, 0.0)

    side = 1.0 if balance(0.0) > 0 else -1.0
    lo, hi = (0.0, side * 2.0 * t.v_max / t.k)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if balance(mid) * side > 0:
            lo = mid
        else:
            hi = mid
    w = 0.5 * (lo + hi)
    return w, current(w)


@dataclass(frozen=True)
class Esc:
    """A bidirectional ESC between a constant supply (the rig's ``v_max``) and the motor: the armature gets the
    command as a duty cycle of the supply (its dead zone: ``voltage_deadband``), the supply delivers the armature's
    input power over the drive's efficiency plus its idle power. Logged as a thrust stand does: the pulse width
    (1500 +- 400 us for +-100 %), unsigned RPM, the supply's voltage and current."""

    eta: float
    p0: float  # [W]


def rows(t: Truth, commands: np.ndarray, esc: Esc | None = None) -> np.ndarray:
    """(4, P) the rig's true [command, current as sensed, omega, thrust] at each command [V] (P,); through an ``esc``
    the command is the pulse width [us] and the current the supply's [A]."""
    out = np.empty((4, commands.size))
    for k, v in enumerate(commands):
        w, i = settle(t, float(v))
        sensed = i + t.e("current_offset", "i0") if esc is None else \
            (drive_voltage(t, float(v)) * i / esc.eta + esc.p0) / t.v_max
        cmd = v if esc is None else 1500.0 + 400.0 * v / t.v_max
        out[:, k] = cmd, sensed, w, quasi_static_thrust(t, w) + t.e("force_offset", "f0")
    return out


def _noise(clean: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """(4,) noise levels left after a hold's averaging: 0.1-0.5 % of each sensed channel's span, drawn per channel
    (the voltage commanded exactly)."""
    span = np.max(np.abs(clean), axis=1)
    return np.concatenate([[0.0], rng.uniform(1e-3, 5e-3, 3)]) * np.maximum(span, 1e-12)


def visible(a: Truth, b: Truth, commands: np.ndarray, noise: np.ndarray, esc: Esc | None = None) -> bool:
    """Whether rigs ``a`` and ``b`` give rows differing by ``VISIBLE`` noise levels (RMS) in some sensed channel."""
    d = np.sqrt(np.mean((rows(a, commands, esc) - rows(b, commands, esc)) ** 2, axis=1))[1:] / noise[1:]
    return bool(np.max(d) >= VISIBLE)


def make_sweep(seed: int, esc: bool = False) -> Sweep:
    """Sweep number ``seed`` (deterministic): a motor from 5 W to 500 W (:func:`.cases.draw_motor`), 12-40 points
    over +-90 % of the supply (both directions, or forward only in one of four), kind clean / one / two / constant /
    constant+one, effects sized as the time-series proving ground draws them, a wrong constant off by 5-50 %.
    ``esc``: through an :class:`Esc` (efficiency 0.85-0.97, idle power 0.5-2 % of the motor's), logged as a thrust
    stand does; only what its channels show is drawn (:data:`ESC_EFFECTS`, :data:`ESC_CONSTANTS`)."""
    rng = np.random.default_rng([seed, 7919] if not esc else [seed, 7919, 1])
    t, _ = draw_motor(rng)
    kind = str(rng.choice(["clean", "one", "one", "two", "constant", "constant+one"]))
    n_fx = {"clean": 0, "one": 1, "two": 2, "constant": 0, "constant+one": 1}[kind]
    names = [str(x) for x in rng.choice(ESC_EFFECTS if esc else SWEEP_EFFECTS, size=n_fx, replace=False)]
    effects = {n: draw_effect(n, t, 1e-3, rng) for n in names}
    errors: dict[str, float] = {}
    if kind.startswith("constant"):
        c = str(rng.choice(ESC_CONSTANTS if esc else SWEEP_CONSTANTS))
        errors[c] = float(rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.5))
    truth = replace(t, effects=effects)
    n = int(rng.integers(12, 41))
    top = 0.9 * t.v_max
    commands = np.linspace(-top, top, n) if rng.uniform() > 0.25 else np.linspace(top / n, top, n)
    drive = Esc(rng.uniform(0.85, 0.97), rng.uniform(0.005, 0.02) * t.v_max ** 2 / t.R / 4) if esc else None
    clean = rows(truth, commands, drive)
    noise = _noise(clean, rng)
    measured = clean + noise[:, None] * rng.standard_normal(clean.shape)
    expected = {f"param:{c}" for c, e in errors.items() if abs(e) > TOLERANCE
                and visible(truth, replace(truth, **{c: getattr(truth, c) / (1.0 + e)}), commands, noise, drive)}
    expected |= {e for e in names if visible(truth, replace(truth, effects={k: v for k, v in effects.items()
                                                                            if k != e}), commands, noise, drive)}
    if drive is None:
        cols = dict(zip(("voltage", "current", "omega", "thrust"), measured, strict=True))
    else:
        cols = {"PWM (µs)": measured[0], "RPM": np.abs(measured[2]) * 60.0 / (2.0 * math.pi),
                "Voltage (V)": t.v_max * (1.0 + 1e-3 * rng.standard_normal(n)), "Current (A)": measured[1],
                "Force (N)": measured[3]}
    return Sweep(seed, kind, cols, _nominal(truth, errors), frozenset(expected), truth)
