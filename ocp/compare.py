"""Optimised vs analytic shapes of the same mission, side by side.

Candidates: the optimised reference of the mission and ``A sin^(2q+1)`` for each requested ``q``, all
with the mission's peak thrust ``A`` and the same period: the shortest period within the limits for
the smallest ``q`` that meets the mission's regularity (so the non-singular parts are comparable, as
in the paper's experiment), aligned to the mission's first reversal and as long as the mission.
For each: duration, peak current/voltage of the ideal feedforward (inf where unbounded), electrical
energy, RMS error to the desired thrust, crossing exponents, and the Section V closed loop
(:mod:`ocp.closed_loop`, 1 ms sampling, saturation, quantisation) tracking it with the reference's
voltage as feedforward.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import trapezoid

from ocp.analytic import SinProfile, reference
from ocp.closed_loop import track
from ocp.errors import MissionError
from ocp.fallback import design_sin
from ocp.mission import Mission
from ocp.optimize import make_plant, optimize
from ocp.plant import DCMotorPlant
from ocp.result import OptimizeResult, _clean
from ocp.theory import min_sin_q


@dataclass
class Candidate:
    """One shape: arrays (N,) on ``t`` [s] and its figures (SI)."""

    label: str
    t: np.ndarray
    thrust: np.ndarray
    omega: np.ndarray
    current: np.ndarray
    voltage: np.ndarray
    figures: dict[str, Any] = field(default_factory=dict)


@dataclass
class CompareResult:
    mission: str
    candidates: list[Candidate]
    optimized: OptimizeResult

    def table(self) -> list[dict[str, Any]]:
        return [{"label": c.label, **c.figures} for c in self.candidates]

    def to_dict(self) -> dict[str, Any]:
        return {"mission": self.mission, "table": _clean(self.table()),
                "optimized_source": self.optimized.source, "optimized_reason": self.optimized.reason}


def _figures(m: Mission, c: Candidate, t_des: np.ndarray, f_des: np.ndarray, exponents: list[float],
             unbounded: bool) -> dict[str, Any]:
    plant = make_plant(m)
    power = c.voltage * c.current
    energy = math.inf if unbounded else float(trapezoid(power, c.t))
    figures: dict[str, Any] = {
        "duration_s": float(c.t[-1] - c.t[0]),
        "peak_current_a": math.inf if unbounded else float(np.max(np.abs(c.current))),
        "peak_voltage_v": math.inf if unbounded else float(np.max(np.abs(c.voltage))),
        "energy_j": energy,
        "thrust_rms_error_n": float(np.sqrt(np.mean((c.thrust - np.interp(c.t, t_des, f_des)) ** 2))),
        "crossing_exponents": exponents,
        "within_limits": (not unbounded) and float(np.max(np.abs(c.current))) <= m.limits.current * 1.001
        and float(np.max(np.abs(c.voltage))) <= m.limits.voltage * 1.001,
    }
    if isinstance(plant, DCMotorPlant):
        theta = np.concatenate([[0.0], np.cumsum(0.5 * (c.omega[1:] + c.omega[:-1]) * np.diff(c.t))])
        loop = track(plant, c.t, c.thrust, c.omega, theta, feedforward=c.voltage)
        lm = loop.metrics
        figures.update({"loop_thrust_rms_n": lm.thrust_rms, "loop_speed_rms_rad_s": lm.speed_rms,
                        "loop_local_speed_error_rad_s": lm.local_speed_error,
                        "loop_peak_voltage_v": lm.peak_voltage, "loop_peak_current_a": lm.peak_current})
    return figures


def compare(m: Mission, qs: tuple[int, ...] = (0, 1, 2, 3)) -> CompareResult:
    """Optimised reference vs ``A sin^(2q+1)`` for each ``q`` in ``qs`` (see module doc)."""
    if not qs or any(q < 0 or q > 10 for q in qs):
        raise MissionError("qs", "give q values in 0..10")
    params = m.motor()
    t_des, f_des = m.desired()
    t_des = t_des - t_des[0]
    opt = optimize(m)
    a = opt.arrays
    cands = [Candidate("optimized" if opt.source == "optimized" else "fallback", a["t"], a["thrust"], a["omega"],
                       a["current"], a["voltage"])]
    cands[0].figures = _figures(m, cands[0], a["t"], a["thrust_desired"], [c["exponent"] for c in opt.crossings],
                                False)
    amp = max(float(np.max(np.abs(f_des))), 1e-6)
    q_min = min_sin_q(m.regularity, m.plant == "dc-motor")
    try:
        period = design_sin(params, m.limits.current, m.limits.voltage, m.regularity, amplitude=amp).profile.period
    except MissionError:
        period = 2.0 * float(t_des[-1])
    sc = np.nonzero(np.sign(f_des[:-1]) * np.sign(f_des[1:]) < 0)[0]
    t = np.linspace(0.0, float(t_des[-1]), max(2, round(float(t_des[-1]) * 1000) + 1))
    for q in qs:
        prof = SinProfile(amp, period, q)
        if sc.size:
            k = int(sc[0])
            phase = (0.0 if f_des[k + 1] > f_des[k] else math.pi) - prof.W * float(t_des[k])
            prof = SinProfile(amp, period, q, phase)
        ref = reference(prof, params, t)
        unbounded = ref.unbounded["current"] or ref.unbounded["voltage"]
        cur = np.where(np.isfinite(ref.current), ref.current, np.sign(ref.current) * 1e9)
        volt = np.where(np.isfinite(ref.voltage), ref.voltage, np.sign(ref.voltage) * 1e9)
        c = Candidate(f"sin^{2 * q + 1}" + (" (mission q)" if q == q_min else ""), t, ref.thrust, ref.omega, cur, volt)
        c.figures = _figures(m, c, t_des, f_des, [float(prof.p)] * len(ref.crossing_times), unbounded)
        cands.append(c)
    return CompareResult(mission=m.name, candidates=cands, optimized=opt)


def plot(result: CompareResult, path: str | Path) -> None:
    """Thrust, speed, current and voltage of every candidate (PNG or SVG by suffix)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(4, 1, figsize=(9, 10), sharex=True)
    for c in result.candidates:
        for ax, y in zip(axes, (c.thrust, c.omega, c.current, c.voltage), strict=True):
            ax.plot(c.t, np.clip(y, -1e3, 1e3), label=c.label, lw=1.2)
    for ax, lab in zip(axes, ("thrust [N]", "speed [rad/s]", "current [A]", "voltage [V]"), strict=True):
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
    opt = result.optimized
    lim_i, lim_v = np.max(np.abs(opt.arrays["current"])), np.max(np.abs(opt.arrays["voltage"]))
    axes[2].set_ylim(-3 * lim_i, 3 * lim_i)
    axes[3].set_ylim(-3 * lim_v, 3 * lim_v)
    axes[0].legend(fontsize=8, ncol=3)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{result.mission}: optimised vs A sin^(2q+1)")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
