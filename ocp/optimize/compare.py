"""Optimised vs analytic shapes of the same mission, side by side.

Candidates: the optimised reference of the mission and, for each requested ``q``, the mission with
every reversal replaced by the ``sin^(2q+1)`` half-wave between the peaks around it
(:class:`~ocp.reference.analytic.SinReversal`; on a sine mission this is exactly ``A sin^(2q+1)``), same levels,
same timing, so only the crossing order differs -- as in the paper's experiment.
For each: duration, peak current/voltage of the ideal feedforward (inf where unbounded), electrical
energy, RMS error to the desired thrust, crossing exponents, and the Section V closed loop
(:mod:`ocp.simulate.closed_loop`, 1 ms sampling, saturation, quantisation) tracking it with the reference's
voltage as feedforward.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.integrate import trapezoid

from ocp.encoding import jsonable
from ocp.errors import MissionError
from ocp.optimize.mission import Mission
from ocp.optimize.result import COMPARE_CURVES as CURVES
from ocp.optimize.result import OptimizeResult, Source
from ocp.optimize.solve import optimize
from ocp.reference.analytic import PiecewiseProfile, SinReversal, reference
from ocp.simulate.closed_loop import track
from ocp.theory.crossings import sign_change_times
from ocp.theory.reversal import min_sin_q


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
        """JSON-ready (:func:`ocp.encoding.jsonable`): the table (an unbounded shape's peaks and energy are ``null``)
        and every candidate's arrays (an unbounded sample has no value: NaN, ``null``; a plot leaves a gap)."""
        curves = [{"label": c.label, **{k: _finite_or_nan(getattr(c, k)) for k in CURVES}}
                  for c in self.candidates]
        return dict(jsonable({"mission": self.mission, "table": self.table(), "candidates": curves,
                              "optimized_source": self.optimized.source, "optimized_reason": self.optimized.reason}))


def _finite_or_nan(a: np.ndarray) -> np.ndarray:
    a = np.asarray(a, float)
    return np.where(np.isfinite(a), a, np.nan)


def _figures(m: Mission, c: Candidate, t_des: np.ndarray, f_des: np.ndarray, exponents: list[float],
             unbounded: bool) -> dict[str, Any]:
    plant = m.drive_plant()
    # an unbounded ideal command has no peak and no energy: None (JSON null)
    energy = None if unbounded else float(trapezoid(c.voltage * c.current, c.t))
    figures: dict[str, Any] = {
        "duration_s": float(c.t[-1] - c.t[0]),
        "peak_current_a": None if unbounded else float(np.max(np.abs(c.current))),
        "peak_voltage_v": None if unbounded else float(np.max(np.abs(c.voltage))),
        "energy_j": energy,
        "thrust_rms_error_n": float(np.sqrt(np.mean((c.thrust - np.interp(c.t, t_des, f_des)) ** 2))),
        "crossing_exponents": exponents,
        "within_limits": (not unbounded) and float(np.max(np.abs(c.current))) <= m.limits.current * 1.001
        and float(np.max(np.abs(c.voltage))) <= m.limits.voltage * 1.001,
    }
    voltage_plant = plant.voltage_plant()  # the Section V loop commands a voltage
    if voltage_plant is not None:
        theta = np.concatenate([[0.0], np.cumsum(0.5 * (c.omega[1:] + c.omega[:-1]) * np.diff(c.t))])
        loop = track(voltage_plant, c.t, c.thrust, c.omega, theta, feedforward=c.voltage)
        lm = loop.metrics
        figures.update({"loop_thrust_rms_n": lm.thrust_rms, "loop_speed_rms_rad_s": lm.speed_rms,
                        "loop_local_speed_error_rad_s": lm.local_speed_error,
                        "loop_peak_voltage_v": lm.peak_voltage, "loop_peak_current_a": lm.peak_current})
    return figures


@dataclass(frozen=True)
class Window:
    """A reversal of the desired thrust: crossing ``t_s`` [s], levels [N] and the times from the
    previous peak (``fall``) and to the next peak (``rise``) [s]."""

    t_s: float
    before: float
    after: float
    fall: float
    rise: float


def mission_reversals(t: np.ndarray, f: np.ndarray) -> list[Window]:
    """The reversals of a desired thrust ``f`` (N,) on ``t`` (N,): each between the peaks of |f| in the
    phases around it (a phase's peak is its signed largest value; the last sample within 0.1 % of it
    before the crossing, the first after)."""
    ts = sign_change_times(t, f)
    if not ts:
        raise MissionError("profile", "compare needs at least one thrust reversal (a sign change)")
    bounds = [float(t[0]), *ts, float(t[-1])]
    out = []
    for k, tk in enumerate(ts):
        levels = []
        for a, b in ((bounds[k], tk), (tk, bounds[k + 2])):
            sel = (t >= a) & (t <= b)
            levels.append((t[sel], f[sel], float(f[sel][np.argmax(np.abs(f[sel]))])))
        (tb, fb, before), (ta, fa, after) = levels
        t_peak_before = float(tb[np.nonzero(np.abs(fb) >= 0.999 * abs(before))[0][-1]])
        t_peak_after = float(ta[np.nonzero(np.abs(fa) >= 0.999 * abs(after))[0][0]])
        out.append(Window(tk, before, after, max(tk - t_peak_before, 1e-3), max(t_peak_after - tk, 1e-3)))
    return out


def reversal_edges(t: np.ndarray, windows: list[Window]) -> list[float]:
    """Where one reversal piece hands over to the next: midway between crossings, and the grid ends."""
    mids = [0.5 * (a.t_s + b.t_s) for a, b in itertools.pairwise(windows)]
    return [float(t[0]), *mids, float(t[-1])]


def compare(m: Mission, qs: tuple[int, ...] = (0, 1, 2, 3)) -> CompareResult:
    """Optimised reference vs ``A sin^(2q+1)`` for each ``q`` in ``qs`` (see module doc)."""
    if not qs or any(q < 0 or q > 10 for q in qs):
        raise MissionError("qs", "give q values in 0..10")
    params = m.motor()
    t_des, f_des = m.desired()
    t_des = t_des - t_des[0]
    opt = optimize(m)
    a = opt.arrays
    cands = [Candidate("optimized" if opt.source is Source.OPTIMIZED else "fallback", a["t"], a["thrust"], a["omega"],
                       a["current"], a["voltage"])]
    cands[0].figures = _figures(m, cands[0], a["t"], a["thrust_desired"], [c.exponent for c in opt.crossings],
                                False)
    windows = mission_reversals(t_des, f_des)
    q_min = min_sin_q(m.regularity, m.drive_plant().voltage_driven)
    t = np.linspace(0.0, float(t_des[-1]), max(2, round(float(t_des[-1]) * 1000) + 1))
    for q in qs:
        prof = PiecewiseProfile(tuple(SinReversal(w.t_s, q, w.before, w.after, w.fall, w.rise) for w in windows),
                                tuple(float(e) for e in reversal_edges(t_des, windows)))
        ref = reference(prof, params, t)
        unbounded = ref.unbounded["current"] or ref.unbounded["voltage"]
        c = Candidate(f"sin^{2 * q + 1}" + (" (mission q)" if q == q_min else ""), t, ref.thrust, ref.omega,
                      ref.current, ref.voltage)
        c.figures = _figures(m, c, t_des, f_des, [float(2 * q + 1)] * len(ref.crossing_times), unbounded)
        cands.append(c)
    return CompareResult(mission=m.name, candidates=cands, optimized=opt)


def plot(data: dict[str, Any], path: str | Path) -> None:
    """Thrust, speed, current and voltage of every candidate of a :meth:`CompareResult.to_dict`
    answer (local or from the service), PNG or SVG by suffix; unbounded samples are left out."""
    from matplotlib.figure import Figure  # object API, no global pyplot state

    fig = Figure(figsize=(9, 10))
    axes = fig.subplots(4, 1, sharex=True)
    channels = ("thrust", "omega", "current", "voltage")
    for c in data["candidates"]:
        for ax, ch in zip(axes, channels, strict=True):
            y = np.array([np.nan if v is None else v for v in c[ch]], dtype=float)
            ax.plot(c["t"], y, label=c["label"], lw=1.2)
    for ax, lab in zip(axes, ("thrust [N]", "speed [rad/s]", "current [A]", "voltage [V]"), strict=True):
        ax.set_ylabel(lab)
        ax.grid(alpha=0.3)
    first = data["candidates"][0]  # the optimised answer sets the current/voltage zoom
    for ax, ch in zip(axes[2:], ("current", "voltage"), strict=True):
        peak = max(abs(v) for v in first[ch] if v is not None)
        ax.set_ylim(-3 * peak, 3 * peak)
    axes[0].legend(fontsize=8, ncol=3)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{data['mission']}: optimised vs sin^(2q+1) reversals")
    fig.tight_layout()
    fig.savefig(path)
