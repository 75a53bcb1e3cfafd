"""The true rig: a brushed DC motor driving a propeller, with hidden physics, and its own integrator.

Equations (SI; written here from the physics, independently of ``ocp``):

* armature:   L di/dt = V_a - R i - k_e w,  with the drive's output V_a = dead_zone(V_cmd(t - lag)) and the
  brush contact drop ``v_b sign(i)`` subtracted, ``sign`` set-valued at i = 0 (a dry contact: the current
  stays zero while |V_a - k_e w| <= v_b);
* rotor:      J dw/dt = k_t i - B w - c_tau w|w| - friction(w) - drag_asym(w) - ripple(theta);
* angle:      dtheta/dt = w;
* thrust:     F_qs = c_f w|w| (+ extra reverse thrust), the load cell sees F = F_lagged + f0, where the wake
  lag is ``tau_F dF_lagged/dt = F_qs - F_lagged``;
* the current sensor reads ``i + i0``.

Integration per sub-step ``h``: the mechanics (w, theta, F_lagged) by classical RK4 whose every stage takes the
armature's step-mean current at that stage's speed (the current's exact exponential solution with that speed held;
with brushes: piecewise, split where the current reaches zero, held at zero inside the contact band); the current at
the step's end exact for the speed's ramp over it (:meth:`Rig._end_current`). Freezing the speed for the whole step
instead (until session 14) left the back-EMF's damping to an explicit Euler step: logs off their own equations by
up to 12 noise levels. The drive's switching instants (lag after each sample) fall on step boundaries.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Truth:
    """Constants of the true rig (SI) and its hidden effects {name: {parameter: value}}."""

    J: float
    B: float
    c_tau: float
    c_f: float
    k: float  # k_t = k_e (SI)
    R: float
    L: float
    v_max: float  # supply [V]: the drive clips the command here
    effects: dict[str, dict[str, float]] = field(default_factory=dict)

    def e(self, name: str, key: str, default: float = 0.0) -> float:
        return self.effects.get(name, {}).get(key, default)


def load_torque(t: Truth) -> Callable[[float, float], float]:
    """The torque [N m] opposing the drive, ``(w [rad/s], theta [rad]) -> tau``: viscous + propeller drag + hidden
    friction/ripple, the effects' parameters looked up once (the integrator's inner loop)."""
    b, c_tau, fx = t.B, t.c_tau, t.effects
    eps = 1e-3 * t.v_max / t.k  # a dry friction's sign, tanh(w / eps): 0.1 % of the no-load speed, sharp (not the
    # identifier's smoothing)
    tau_c = t.e("coulomb_friction", "tau_c") if "coulomb_friction" in fx else None
    tau_s, ws = (t.e("stribeck", "tau_s"), t.e("stribeck", "omega_s")) if "stribeck" in fx else (None, 1.0)
    delta = t.e("stribeck", "delta", 2.0)  # the film's decay exponent (2: Gaussian, the catalogue's; 1: Tustin's)
    dc_tau = t.e("drag_asymmetry", "dc_tau") if "drag_asymmetry" in fx else None
    ripple = (t.e("cogging", "amplitude"), t.e("cogging", "periods"), t.e("cogging", "phase")) \
        if "cogging" in fx else None
    # harmonics of the ripple (relative amplitudes at 2 and 3 times its count, their phases): a slotted motor's
    # cogging is periodic in the angle, not a pure sine
    overtones = [(t.e("cogging", f"h{m}"), m, t.e("cogging", f"phase{m}")) for m in (2, 3) if t.e("cogging", f"h{m}")]

    def tau(w: float, theta: float) -> float:
        x = b * w + c_tau * w * abs(w)
        if tau_c is not None:
            x += tau_c * math.tanh(w / eps)
        if tau_s is not None:
            r = w / ws
            x += tau_s * math.exp(-(r ** 2 if delta == 2.0 else abs(r) ** delta)) * math.tanh(w / eps)
        if dc_tau is not None and w < 0:
            x += dc_tau * w * abs(w)
        if ripple is not None:
            x += ripple[0] * math.sin(ripple[1] * theta + ripple[2])
            for h, m, ph in overtones:
                x += ripple[0] * h * math.sin(m * ripple[1] * theta + ph)
        return x

    return tau


def quasi_static_thrust(t: Truth, w: float) -> float:
    f = t.c_f * w * abs(w)
    if "thrust_asymmetry" in t.effects and w < 0:
        f += t.e("thrust_asymmetry", "dc_f") * w * abs(w)
    return f


def drive_voltage(t: Truth, v_cmd: float) -> float:
    """What the drive puts out [V]: the command clipped to the supply, then the dead zone (hard): every command
    shifted by the band, or with ``gap`` set (no case draws it; tests do), nothing inside the band and the whole
    command beyond it (a minimum pulse width)."""
    v = max(-t.v_max, min(t.v_max, v_cmd))
    if "voltage_deadband" in t.effects:
        d = t.e("voltage_deadband", "v_db")
        if t.e("voltage_deadband", "gap"):
            return v if abs(v) >= d else 0.0
        v = math.copysign(max(abs(v) - d, 0.0), v)
    return v


def _exp_segment(i0: float, i_ss: float, tau_e: float, h: float) -> tuple[float, float]:
    """Exact solution of ``tau_e di/dt = i_ss - i`` from ``i0`` over ``h`` [s]: (end current [A], integral [A s])."""
    a = math.exp(-h / tau_e)
    return i_ss + (i0 - i_ss) * a, i_ss * h + (i0 - i_ss) * (1.0 - a) * tau_e


def brush_current_step(u: float, v_b: float, R: float, L: float, i0: float, h: float) -> tuple[float, float]:
    """Exact current step through brushes: ``L di/dt = u - R i - v_b sign(i)``, sign set-valued at 0.

    ``u = V_a - k_e w`` [V] (frozen over the step), ``v_b`` brush drop [V], ``R`` [ohm], ``L`` [H], ``i0`` the
    current [A] at the start, ``h`` the step [s]. The drop opposes the current; where the current reaches zero
    the step is split, and the current stays zero while ``|u| <= v_b`` (the contact takes up the whole
    ``u``). Returns (end current [A], mean current over the step [A]).
    """
    tau_e, left, i, q = L / R, h, i0, 0.0
    for _ in range(3):  # at most: decay to zero, then stick or restart the other way
        s = 1.0 if i > 0.0 else -1.0 if i < 0.0 else (1.0 if u > v_b else -1.0 if u < -v_b else 0.0)
        if s == 0.0:  # stuck inside the band: i = 0 for the rest of the step
            return 0.0, q / h
        # eq:dc_electrical with the brush drop v_b sign(i), sign(i) = s on this segment
        i_ss = (u - s * v_b) / R
        t_zero = tau_e * math.log((i - i_ss) / -i_ss) if s * i_ss < 0.0 and i != 0.0 else math.inf
        if t_zero >= left:
            i, dq = _exp_segment(i, i_ss, tau_e, left)
            return i, (q + dq) / h
        q += _exp_segment(i, i_ss, tau_e, t_zero)[1]
        i, left = 0.0, left - t_zero
    return i, q / h


class Rig:
    """State and stepping of the true rig. ``step(v_cmd_at, t0, dt, m)`` advances one log sample."""

    def __init__(self, truth: Truth) -> None:
        self.t = truth
        self.w = self.i = self.theta = 0.0
        self.f_lag = 0.0
        self.tau_f = truth.e("thrust_lag", "tau", 0.0)
        self._torque = load_torque(truth)

    def _armature(self, va: float, w: float, h: float) -> tuple[float, float]:
        """(end current [A], mean current [A]) over ``h`` [s] from the present current, the drive putting out
        ``va`` [V] and the speed held at ``w`` [rad/s]: eq:dc_electrical, exact for that speed."""
        t = self.t
        if "brush_drop" in t.effects:
            return brush_current_step(va - t.k * w, t.e("brush_drop", "v_b"), t.R, t.L, self.i, h)
        i_ss = (va - t.k * w) / t.R
        a = math.exp(-h * t.R / t.L)
        return i_ss + (self.i - i_ss) * a, i_ss + (self.i - i_ss) * (1.0 - a) * t.L / (t.R * h)

    def _end_current(self, va: float, w0: float, w1: float, h: float) -> float:
        """The current [A] after ``h`` [s] with the speed moving linearly from ``w0`` to ``w1`` [rad/s]:
        eq:dc_electrical under the ramp ``u(s) = a + b s`` (``b = -k_e (w1 - w0) / h``) is exact, the step from the
        speed held at ``w1`` plus ``(b / R) (h e^-x - (L / R)(1 - e^-x))``, ``x = h R / L``. With brushes the drop is
        a constant ``v_b sign(i)`` while the current keeps its sign; a step where it reaches zero is taken at the
        mean speed."""
        t = self.t
        end = self._armature(va, w1, h)[0]
        if "brush_drop" in t.effects and not end * self.i > 0.0:
            return self._armature(va, 0.5 * (w0 + w1), h)[0]
        e = math.exp(-h * t.R / t.L)
        return end - t.k * (w1 - w0) / (h * t.R) * (h * e - t.L / t.R * (1.0 - e))

    def substep(self, v_cmd: float, h: float) -> None:
        """Advance ``h`` [s] (:meth:`advance`, one step)."""
        self.advance(v_cmd, h, 1)

    def advance(self, v_cmd: float, h: float, m: int) -> None:
        """Advance ``m`` steps of ``h`` [s] under the held command ``v_cmd`` [V]: RK4 on the rotor and thrust lag, each
        stage driven by the armature's exact mean current over the step at that stage's speed (so the back-EMF's
        damping is inside the stages: with L/R far below ``h`` the current follows the speed within the step, as it
        does physically); then the current (:meth:`_end_current`). (Without brushes, :meth:`_armature` and
        :meth:`_end_current` are written out with their factors formed once per call, the arithmetic unchanged: the
        inner loop of every proving-ground log.)"""
        t = self.t
        va = drive_voltage(t, v_cmd)
        k, r, el, j, tau_f, torque = t.k, t.R, t.L, t.J, self.tau_f, self._torque
        brush = t.e("brush_drop", "v_b") if "brush_drop" in t.effects else None
        a = math.exp(-h * r / el)
        oma, rh, hh, h6, bend = 1.0 - a, r * h, 0.5 * h, h / 6.0, h * a - el / r * (1.0 - a)

        def f(w: float, theta: float, f_lag: float, i0: float) -> tuple[float, float, float]:
            if brush is None:  # _armature's mean current
                i_ss = (va - k * w) / r
                i = i_ss + (i0 - i_ss) * oma * el / rh
            else:
                i = brush_current_step(va - k * w, brush, r, el, i0, h)[1]
            # eq:dc_mechanical, the angle, the wake lag
            return (k * i - torque(w, theta)) / j, w, (quasi_static_thrust(t, w) - f_lag) / tau_f if tau_f > 0 else 0.0

        for _ in range(m):
            w0, th0, fl0, i0 = self.w, self.theta, self.f_lag, self.i
            k1 = f(w0, th0, fl0, i0)
            k2 = f(w0 + hh * k1[0], th0 + hh * k1[1], fl0 + hh * k1[2], i0)
            k3 = f(w0 + hh * k2[0], th0 + hh * k2[1], fl0 + hh * k2[2], i0)
            k4 = f(w0 + h * k3[0], th0 + h * k3[1], fl0 + h * k3[2], i0)
            self.w = w0 + h6 * (k1[0] + 2 * k2[0] + 2 * k3[0] + k4[0])
            self.theta = th0 + h6 * (k1[1] + 2 * k2[1] + 2 * k3[1] + k4[1])
            self.f_lag = fl0 + h6 * (k1[2] + 2 * k2[2] + 2 * k3[2] + k4[2])
            if brush is None:  # _end_current
                i_ss = (va - k * self.w) / r
                self.i = i_ss + (i0 - i_ss) * a - k * (self.w - w0) / rh * bend
            else:
                self.i = self._end_current(va, w0, self.w, h)

    def thrust(self) -> float:
        f = self.f_lag if self.tau_f > 0 else quasi_static_thrust(self.t, self.w)
        return f + self.t.e("force_offset", "f0")

    def sensed_current(self) -> float:
        return self.i + self.t.e("current_offset", "i0")


def run(truth: Truth, command: Callable[[int, np.ndarray], float], n: int, dt: float, lag: float,
        substeps: int) -> tuple[np.ndarray, np.ndarray]:
    """Simulate ``n`` log samples. ``command(k, sensed)`` returns the command issued at sample k from the
    sensors just read (sensed = [w, i_sensed, theta, F]); the drive applies it ``lag`` seconds later.

    Returns (truth samples (4, n): w, sensed current, theta, thrust at t_k; issued commands (n,)).
    """
    rig = Rig(truth)
    out = np.empty((4, n))
    cmds = np.zeros(n)
    # the command of sample j is in force over [j dt + lag, (j + 1) dt + lag): within each sample interval the
    # drive switches ``phi`` after its start, which a piece boundary meets exactly (sub-steps of at most dt/substeps)
    whole, phi = divmod(lag, dt)
    cut = phi > 1e-9 * dt
    pieces = [(phi, math.ceil(substeps * phi / dt)), (dt - phi, math.ceil(substeps * (dt - phi) / dt))] if cut \
        else [(dt, substeps)]
    for k in range(n):
        out[:, k] = (rig.w, rig.sensed_current(), rig.theta, rig.thrust())
        cmds[k] = command(k, out[:, k])
        for p, (span, m) in enumerate(pieces):
            j = k - int(whole) - (1 if cut and p == 0 else 0)
            v = float(cmds[j]) if j >= 0 else 0.0
            rig.advance(v, span / m, m)
    return out, cmds
