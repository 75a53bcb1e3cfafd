"""True-rig physics of a brushed DC motor with a bidirectional propeller, and its integrator.

Independent of the checker: own formulas, own fixed-step integrator.

State: armature current ``i`` [A], speed ``w`` [rad/s], rotor angle ``th`` [rad], measured-side thrust
state ``F`` [N] (the lagged thrust when a wake lag is present, else unused).

Equations (SI)::

    L di/dt  = u_motor - R i - g_brush(i) - k w
    J dw/dt  = k i - B w - c_tau(w) w|w| - tau_fric(w) - tau_cog(th)
    dth/dt   = w
    thrust   = c_f(w) w|w|                  (quasi-static) or
    dF/dt    = (c_f(w) w|w| - F) / tau_F    (wake lag)

with ``g_brush(i) = V_b tanh(i / i_b)``, ``tau_fric(w) = (tau_c + tau_s exp(-(w/w_s)^2)) tanh(w / w_0)`` and
``tau_cog(th) = A_cog (sin(N th + p1) + a2 sin(2 N th + p2))``.

Integrator (per substep ``h``, command frozen): a half-step of the mechanics (explicit), an exact
exponential update of the current over ``h`` with speed frozen at the half-step value and the brush drop
linearised about the current at the substep start (Rosenbrock-style, so any L/R is stable), then an
explicit-midpoint update of speed and angle with the time-averaged current of the exponential update and
the angle-averaged cogging torque over the substep (so cogging faster than the substep averages out correctly
instead of aliasing). The stiff friction slope near zero speed (tanh smoothing of sign(w)) is treated
linearly-implicitly in both speed updates. Second-order in ``h`` for smooth slow dynamics (first-order
contributions remain from the linearised brush drop and friction), exact for the fast current.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass


@dataclass
class RigTruth:
    """True physical constants and effect parameters of one rig (SI units).

    Attributes:
        V_supply: drive supply voltage [V]; the H-bridge clips its output to +-V_supply.
        R: armature resistance [ohm]. L: armature inductance [H]. k: torque/back-emf constant [N m/A = V s/rad].
        J: rotor + propeller inertia [kg m^2]. B: viscous friction [N m s/rad].
        c_tau: forward propeller drag coefficient [N m s^2/rad^2]; c_tau_rev: reverse one.
        c_f: forward thrust coefficient [N s^2/rad^2]; c_f_rev: reverse one.
        tau_coulomb: dry (Coulomb) friction torque [N m]; tau_stribeck: breakaway excess [N m];
        w_stribeck: Stribeck speed scale [rad/s]; w_smooth: sign() smoothing speed of friction [rad/s].
        V_brush: brush voltage drop [V]; i_brush: current scale of its tanh smoothing [A].
        deadband: drive dead band half-width [V]; deadband_mode: "zero" (inside -> 0) or "shift"
            (outside -> V - sign(V) deadband).
        delay: transport delay between command and motor [s].
        thrust_tau: wake-inflow first-order thrust lag [s] (0: none).
        cog_amp: cogging amplitude [N m]; cog_N: periods per revolution; cog_p1, cog_p2: phases [rad];
        cog_a2: relative amplitude of the second harmonic [-].
    """

    V_supply: float
    R: float
    L: float
    k: float
    J: float
    B: float
    c_tau: float
    c_tau_rev: float
    c_f: float
    c_f_rev: float
    tau_coulomb: float = 0.0
    tau_stribeck: float = 0.0
    w_stribeck: float = 1.0
    w_smooth: float = 1.0
    V_brush: float = 0.0
    i_brush: float = 1.0
    deadband: float = 0.0
    deadband_mode: str = "zero"
    delay: float = 0.0
    thrust_tau: float = 0.0
    cog_amp: float = 0.0
    cog_N: int = 0
    cog_p1: float = 0.0
    cog_p2: float = 0.0
    cog_a2: float = 0.0

    def to_dict(self) -> dict:
        """Plain dict of all fields (JSON-serialisable)."""
        return asdict(self)


def no_load_speed(p: RigTruth, voltage: float) -> float:
    """Steady forward speed [rad/s] at a constant motor voltage [V] >= 0 with B and forward drag only.

    Solves ``k (V - k w) / R = B w + c_tau w^2`` for the positive root.
    """
    a = p.c_tau
    b = p.B + p.k * p.k / p.R
    c = -p.k * voltage / p.R
    if a <= 0.0:
        return -c / b
    return (-b + math.sqrt(b * b - 4.0 * a * c)) / (2.0 * a)


class Rig:
    """Integrates the true rig with a piecewise-constant drive command.

    Args:
        p: the true constants and effects.
        h_max: largest substep [s]; ``advance`` splits any interval into ceil(T / h) equal substeps.
        max_sub: cap on substeps per ``advance`` call used when refining for cogging [-].
    """

    def __init__(self, p: RigTruth, h_max: float, max_sub: int = 32, theta0: float = 0.0) -> None:
        self.p = p
        self.h_max = float(h_max)
        self.max_sub = int(max_sub)
        self.i = 0.0
        self.w = 0.0
        self.th = float(theta0)
        self.F = 0.0
        self.n_steps = 0

    def drive(self, cmd: float) -> float:
        """Voltage [V] the H-bridge puts on the motor for a command [V]: dead band, then supply clip."""
        p = self.p
        u = cmd
        if p.deadband > 0.0:
            if abs(u) < p.deadband:
                u = 0.0
            elif p.deadband_mode == "shift":
                u = u - math.copysign(p.deadband, u)
        return max(-p.V_supply, min(p.V_supply, u))

    def thrust_qs(self, w: float) -> float:
        """Quasi-static thrust [N] at speed w [rad/s]."""
        c = self.p.c_f if w >= 0.0 else self.p.c_f_rev
        return c * w * abs(w)

    def thrust(self) -> float:
        """Current true thrust [N] (lagged state if a wake lag is present)."""
        return self.F if self.p.thrust_tau > 0.0 else self.thrust_qs(self.w)

    def load_torque(self, w: float, th: float) -> float:
        """Torque [N m] opposing the motor at speed w [rad/s] and angle th [rad] (no cogging averaging)."""
        p = self.p
        c = p.c_tau if w >= 0.0 else p.c_tau_rev
        tq = p.B * w + c * w * abs(w)
        if p.tau_coulomb > 0.0 or p.tau_stribeck > 0.0:
            x = w / p.w_stribeck
            tq += (p.tau_coulomb + p.tau_stribeck * math.exp(-x * x)) * math.tanh(w / p.w_smooth)
        if p.cog_amp > 0.0:
            n = p.cog_N
            tq += p.cog_amp * (math.sin(n * th + p.cog_p1) + p.cog_a2 * math.sin(2 * n * th + p.cog_p2))
        return tq

    def advance(self, u: float, T: float) -> None:
        """Integrate T seconds with the motor voltage u [V] held constant (u already through ``drive``)."""
        if T <= 0.0:
            return
        p = self.p
        n = max(1, math.ceil(T / self.h_max - 1e-9))
        if p.cog_amp > 0.0:
            h_cog = 2.0 * math.pi / (p.cog_N * abs(self.w) + 1e-12) / 12.0
            n = max(n, min(self.max_sub, math.ceil(T / h_cog)))
        h = T / n
        R, L, k, J = p.R, p.L, p.k, p.J
        B, ct, ctr, cf, cfr = p.B, p.c_tau, p.c_tau_rev, p.c_f, p.c_f_rev
        tc, ts, ws, w0 = p.tau_coulomb, p.tau_stribeck, p.w_stribeck, p.w_smooth
        fric = tc > 0.0 or ts > 0.0
        Vb, ib = p.V_brush, p.i_brush
        cog = p.cog_amp > 0.0
        A, N, p1, p2, a2 = p.cog_amp, p.cog_N, p.cog_p1, p.cog_p2, p.cog_a2
        tauF = p.thrust_tau
        aF = 1.0 - math.exp(-h / tauF) if tauF > 0.0 else 1.0
        i, w, th, F = self.i, self.w, self.th, self.F
        exp, tanh, sin, cos = math.exp, math.tanh, math.sin, math.cos

        def load(w_: float, th_a: float, th_b: float) -> float:
            c = ct if w_ >= 0.0 else ctr
            tq = B * w_ + c * w_ * abs(w_)
            if fric:
                x = w_ / ws
                tq += (tc + ts * exp(-x * x)) * tanh(w_ / w0)
            if cog:
                d = th_b - th_a
                if abs(N * d) < 1e-3:
                    tm = 0.5 * (th_a + th_b)
                    tq += A * (sin(N * tm + p1) + a2 * sin(2 * N * tm + p2))
                else:  # exact mean of the cogging torque over the angle interval [th_a, th_b]
                    s1 = (cos(N * th_a + p1) - cos(N * th_b + p1)) / (N * d)
                    s2 = (cos(2 * N * th_a + p2) - cos(2 * N * th_b + p2)) / (2 * N * d)
                    tq += A * (s1 + a2 * s2)
            return tq

        for _ in range(n):
            # half-step mechanics with the current at the substep start
            wdot0 = (k * i - load(w, th, th + 0.5 * h * w)) / J
            dm = 0.0
            if fric:  # linearly-implicit treatment of the stiff friction slope near zero speed
                x = w / ws
                tw = tanh(w / w0)
                dm = (tc + ts * exp(-x * x)) * (1.0 - tw * tw) / (w0 * J)
            w_h = w + 0.5 * h * wdot0 / (1.0 + 0.5 * h * dm)
            # exact exponential current update, speed frozen at w_h, brush drop linearised at i
            if Vb > 0.0:
                tb = tanh(i / ib)
                g = Vb * tb
                gp = Vb / ib * (1.0 - tb * tb)
                Re = R + gp
                ue = u - g + gp * i
            else:
                Re, ue = R, u
            i_inf = (ue - k * w_h) / Re
            x = h * Re / L
            a = exp(-x)
            i_new = i_inf + (i - i_inf) * a
            i_avg = i_inf + (i - i_inf) * ((1.0 - a) / x if x > 1e-9 else 1.0 - 0.5 * x)
            # midpoint mechanics with the time-averaged current and angle-averaged cogging
            th_new = th + h * w_h
            if fric:
                x = w_h / ws
                tw = tanh(w_h / w0)
                dm = (tc + ts * exp(-x * x)) * (1.0 - tw * tw) / (w0 * J)
            w_new = w + h * (k * i_avg - load(w_h, th, th_new)) / J / (1.0 + 0.5 * h * dm)
            if tauF > 0.0:
                c = cf if w_h >= 0.0 else cfr
                F += (c * w_h * abs(w_h) - F) * aF
            i, w, th = i_new, w_new, th_new
        self.i, self.w, self.th, self.F = i, w, th, F
        self.n_steps += n


def stiffness_step(p: RigTruth, w_top: float) -> float:
    """Largest substep [s] for accuracy of the slow (mechanical) dynamics of the rig ``p``.

    ``w_top`` [rad/s] is the top speed; returns min of tau_em/40 (electromechanical + drag + viscous
    damping time) and four friction smoothing times J w_0 / (tau_c + tau_s).
    """
    damp = p.k * p.k / p.R + p.B + 2.0 * max(p.c_tau, p.c_tau_rev) * w_top
    h = p.J / damp / 40.0
    if p.tau_coulomb + p.tau_stribeck > 0.0:  # friction slope is linearly implicit: h * slope / J <= 4
        h = min(h, 4.0 * p.J * p.w_smooth / (p.tau_coulomb + p.tau_stribeck))
    return h
