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

Integration per sub-step ``h``: the current by its exact exponential solution with the speed frozen
over the step (with brushes: piecewise, split where the current reaches zero, held at zero inside the
contact band), the mechanics (w, theta, F_lagged) by classical RK4 with the step-mean current.
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


def _sgn(x: float, eps: float) -> float:
    return math.tanh(x / eps)


def load_torque(t: Truth, w: float, theta: float) -> float:
    """Torque [N m] opposing the drive: viscous + propeller drag + hidden friction/ripple."""
    tau = t.B * w + t.c_tau * w * abs(w)
    eps = 1e-3 * t.v_max / t.k  # 0.1 % of the no-load speed: sharp, not the identifier's smoothing
    if "coulomb_friction" in t.effects:
        tau += t.e("coulomb_friction", "tau_c") * _sgn(w, eps)
    if "stribeck" in t.effects:
        ws = t.e("stribeck", "omega_s")
        tau += t.e("stribeck", "tau_s") * math.exp(-(w / ws) ** 2) * _sgn(w, eps)
    if "drag_asymmetry" in t.effects and w < 0:
        tau += t.e("drag_asymmetry", "dc_tau") * w * abs(w)
    if "cogging" in t.effects:
        n = t.e("cogging", "periods")
        tau += t.e("cogging", "amplitude") * math.sin(n * theta + t.e("cogging", "phase"))
    return tau


def quasi_static_thrust(t: Truth, w: float) -> float:
    f = t.c_f * w * abs(w)
    if "thrust_asymmetry" in t.effects and w < 0:
        f += t.e("thrust_asymmetry", "dc_f") * w * abs(w)
    return f


def drive_voltage(t: Truth, v_cmd: float) -> float:
    """What the drive puts out [V]: the command clipped to the supply, then the dead zone (hard)."""
    v = max(-t.v_max, min(t.v_max, v_cmd))
    if "voltage_deadband" in t.effects:
        d = t.e("voltage_deadband", "v_db")
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

    def _mech(self, w: float, theta: float, f_lag: float, i: float) -> tuple[float, float, float]:
        t = self.t
        dw = (t.k * i - load_torque(t, w, theta)) / t.J
        df = (quasi_static_thrust(t, w) - f_lag) / self.tau_f if self.tau_f > 0 else 0.0
        return dw, w, df

    def substep(self, v_cmd: float, h: float) -> None:
        t = self.t
        va = drive_voltage(t, v_cmd)
        if "brush_drop" in t.effects:
            i_end, i_mean = brush_current_step(va - t.k * self.w, t.e("brush_drop", "v_b"), t.R, t.L, self.i, h)
        else:  # eq:dc_electrical, exact over the step
            i_ss = (va - t.k * self.w) / t.R
            a = math.exp(-h * t.R / t.L)
            i_mean = i_ss + (self.i - i_ss) * (1.0 - a) * t.L / (t.R * h)
            i_end = i_ss + (self.i - i_ss) * a
        y = (self.w, self.theta, self.f_lag)
        k1 = self._mech(*y, i_mean)
        k2 = self._mech(*(y[j] + 0.5 * h * k1[j] for j in range(3)), i_mean)
        k3 = self._mech(*(y[j] + 0.5 * h * k2[j] for j in range(3)), i_mean)
        k4 = self._mech(*(y[j] + h * k3[j] for j in range(3)), i_mean)
        self.w, self.theta, self.f_lag = (y[j] + h / 6.0 * (k1[j] + 2 * k2[j] + 2 * k3[j] + k4[j]) for j in range(3))
        self.i = i_end

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
    h = dt / substeps
    out = np.empty((4, n))
    cmds = np.zeros(n)
    for k in range(n):
        out[:, k] = (rig.w, rig.sensed_current(), rig.theta, rig.thrust())
        cmds[k] = command(k, out[:, k])
        for s in range(substeps):
            tau = (k + s / substeps) * dt - lag  # command in force at this sub-step
            j = math.floor(tau / dt + 1e-9)
            rig.substep(float(cmds[j]) if j >= 0 else 0.0, h)
    return out, cmds
