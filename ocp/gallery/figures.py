"""Matplotlib renderings of the gallery's regenerated data (one function per paper figure).

Uses the object-oriented API on an Agg canvas (``matplotlib.figure.Figure``, no pyplot): no GUI
backend is selected and no global matplotlib state is touched, in this module or anywhere in ``ocp``.
Each ``fig_*`` function returns a :class:`~matplotlib.figure.Figure`; :func:`save` writes PNG and SVG.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

from ocp.gallery.experiment import CaseRun
from ocp.gallery.interaction import InteractionReference
from ocp.model.params import MotorParams
from ocp.reference.analytic import LocalReversal, SinProfile, reference
from ocp.reference.trajectory import Reference
from ocp.theory.normal_form import normal_form_drift, normal_form_gain
from ocp.theory.reversal import crossing_class, feasibility_bounds, regularity_label

COLORS = ("tab:blue", "tab:red", "tab:olive", "tab:green", "tab:purple", "tab:brown")
#: thrust orders p of the six cases of Fig. dc_reference_cases (Cases 1, 4, 5 are Section V's p = 1, 5, 7)
CASE_ORDERS: tuple[int, ...] = (1, 2, 3, 5, 7, 9)


def _figure(width: float, height: float) -> Figure:
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, out: Path, name: str) -> list[str]:
    """Write ``name.png`` and ``name.svg`` into ``out``; returns the file names."""
    files = [f"{name}.png", f"{name}.svg"]
    fig.savefig(out / files[0], dpi=130)
    fig.savefig(out / files[1])
    return files


def fig_f2_map(k: float) -> Figure:
    """Fig. f2_map: drift ``f2`` and input gain ``g2`` of eq. sys2 vs the normalised thrust x2."""
    x2 = np.linspace(-2.0, 2.0, 801)
    fig = _figure(6.0, 3.4)
    ax = fig.add_subplot()
    ax.plot(x2, normal_form_drift(x2, k), label=rf"drift $f_2=-2k\,\mathrm{{sgn}}(x_2)|x_2|^{{3/2}}$, k={k:g}")
    ax.plot(x2, normal_form_gain(x2), label=r"input gain $g_2=2\sqrt{|x_2|}$")
    ax.plot([0.0], [0.0], "ko", label="reversal: $g_2=0$")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.axvline(0.0, color="0.6", lw=0.6)
    ax.set(xlabel="normalised thrust $x_2$", ylabel="value", title="Normal form (eq. sys2)")
    ax.legend(fontsize=8)
    return fig


def fig_trjphase(k: float, u_low: float, u_high: float) -> Figure:
    """Fig. trjphase: the feasibility set S (eq. feasibility_set) in the (y', y'') plane."""
    yd = np.linspace(-4.0, 4.0, 1601)
    lo, hi = feasibility_bounds(yd, k, u_low, u_high)
    fig = _figure(6.0, 4.0)
    ax = fig.add_subplot()
    ax.fill_between(yd, lo, hi, color="tab:blue", alpha=0.25, label=r"$\mathbb{S}$")
    ax.plot(yd, hi, color="tab:blue", label=rf"$u=\overline{{u}}={u_high:g}$")
    ax.plot(yd, lo, color="tab:red", label=rf"$u=-\underline{{u}}=-{u_low:g}$")
    ax.axvline(0.0, color="k", ls="--", lw=1.0, label=r"$\dot y=0$ excluded")
    ax.set(xlabel=r"$\dot y_d$", ylabel=r"$\ddot y_d$", title=f"Feasibility set S (k = {k:g})")
    ax.legend(fontsize=8)
    return fig


def case_profile(p: int, amplitude: float = 0.5, period: float = 2.0) -> SinProfile | LocalReversal:
    """Thrust profile of one Fig. dc_reference_cases case: odd ``p``: ``A sin^p``; even ``p`` (touch, no sign
    change): a local reversal ``alpha (t - T/2)^p`` blended into ``A`` on both sides."""
    if p % 2:
        return SinProfile(amplitude, period, (p - 1) // 2)
    return LocalReversal.between(amplitude, amplitude, period / 2, p, period / 2)


def reference_case(params: MotorParams, p: int, amplitude: float = 0.5, period: float = 2.0) -> Reference:
    """Exact reference of one Fig. dc_reference_cases case over one period [0, period] at 1 kHz."""
    t = np.linspace(0.0, period, round(period * 1000) + 1)
    return reference(case_profile(p, amplitude, period), params, t)


def one_sided_limits(profile: SinProfile | LocalReversal, params: MotorParams, t_s: float, channel: str,
                     offset: float = 1e-9) -> tuple[float, float]:
    """(left, right) values of ``channel`` just before and after the crossing ``t_s`` [s] (closed forms at
    ``t_s -+ offset``): their signs are the one-sided limits' signs where the channel is unbounded."""
    ref = reference(profile, params, np.array([t_s - offset, t_s + offset]))
    values = getattr(ref, channel)
    return float(values[0]), float(values[1])


def crossing_markers(profile: SinProfile | LocalReversal, params: MotorParams, ref: Reference, channel: str,
                     lim: float) -> list[tuple[float, float, str]]:
    """Markers ``(t [s], y, side)`` for the samples of ``ref`` exactly on a crossing where ``channel`` is
    unbounded: one at ``+-lim`` per one-sided limit (``side`` "left" / "right"), so a channel that dives to
    -inf on one side and returns from +inf on the other shows both."""
    y = getattr(ref, channel)
    out = []
    for t_s in ref.crossing_times:
        k = int(np.argmin(np.abs(ref.t - t_s)))
        if abs(ref.t[k] - t_s) > 1e-9 * max(1.0, abs(t_s)) or np.isfinite(y[k]):
            continue
        left, right = one_sided_limits(profile, params, t_s, channel)
        out += [(float(ref.t[k]), float(np.sign(left)) * lim, "left"),
                (float(ref.t[k]), float(np.sign(right)) * lim, "right")]
    return out


def _clipped(ax: Axes, t: np.ndarray, y: np.ndarray, far: np.ndarray, color: str, label: str,
             markers: list[tuple[float, float, str]]) -> None:
    """Plot ``y`` clipped to 1.5x its peak away from the crossings, broken at infinite samples; mark
    clipped samples and both one-sided limits at a crossing sample (``markers``, :func:`crossing_markers`)."""
    lim = plot_limit(y, far)
    big = np.isfinite(y) & (np.abs(y) > lim)
    ax.plot(t, np.clip(np.where(np.isfinite(y), y, np.nan), -lim, lim), color=color, label=label)
    if big.any():
        ax.plot(t[big], np.sign(y[big]) * lim, "^", color="k", ms=4, label="clipped (unbounded)")
    for side, style in (("left", "<"), ("right", ">")):
        pts = [(tm, ym) for tm, ym, sd in markers if sd == side]
        if pts:
            ax.plot(*zip(*pts, strict=True), style, color="tab:red", ms=6, label=f"{side} limit ±inf")
    ax.set_ylim(-1.1 * lim, 1.1 * lim)


def plot_limit(y: np.ndarray, far: np.ndarray) -> float:
    """1.5x the largest finite ``|y|`` on the ``far`` samples (away from crossings); 1 when there is none."""
    finite_far = np.abs(y[far & np.isfinite(y)])
    return 1.5 * float(finite_far.max()) if finite_far.size and finite_far.max() > 0 else 1.0


def fig_dc_reference_cases(params: MotorParams) -> Figure:
    """Fig. dc_reference_cases: ideal V, i, omega, F for six crossing orders (rows: channels)."""
    fig = _figure(13.0, 7.5)
    axes = fig.subplots(4, len(CASE_ORDERS), sharex=True)
    channels = (("voltage", "V [V]"), ("current", "i [A]"), ("omega", r"$\omega$ [rad/s]"), ("thrust", "F [N]"))
    for j, p in enumerate(CASE_ORDERS):
        ref = reference_case(params, p)
        far = np.ones(ref.t.shape, dtype=bool)
        for ts in ref.crossing_times:
            far &= np.abs(ref.t - ts) > 0.05
        cls = crossing_class(p)
        axes[0, j].set_title(f"Case {j + 1}: p={p}\ni {regularity_label(cls.current)}, "
                             f"V {regularity_label(cls.voltage)}", fontsize=8)
        prof = case_profile(p)
        for r, (ch, lab) in enumerate(channels):
            y = getattr(ref, ch)
            _clipped(axes[r, j], ref.t, y, far, COLORS[j], ch,
                     crossing_markers(prof, params, ref, ch, plot_limit(y, far)))
            if j == 0:
                axes[r, j].set_ylabel(lab)
        axes[-1, j].set_xlabel("t [s]")
    fig.suptitle("Ideal references (eqs. current_reference, voltage_reference); ▲ = clipped; "
                 "◀ ▶ = left / right limit (±inf) at a sample on a reversal")
    return fig


def fig_interaction(refs: list[InteractionReference], u_bound: float) -> Figure:
    """Fig. admit_exa + its actuator-aware version: x2d and the input of eq. tracking_u_motiv."""
    fig = _figure(11.0, 6.0)
    axes = fig.subplots(2, len(refs), sharex=True)
    for j, r in enumerate(refs):
        ax = axes[0, j]
        ax.plot(r.t, r.x2d, color="tab:blue", label="ideal (linear crossings)")
        ax.plot(r.t, r.x2s, color="tab:orange", label="shaped (p = 5 crossings)")
        ax.plot(r.crossings, np.zeros(len(r.crossings)), "k|", ms=10)
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.set(title=f"{r.law.value}: thrust reference", ylabel="$x_{2d}$")
        ax.legend(fontsize=8)
        ax = axes[1, j]
        lim = 2.0 * u_bound
        big = ~np.isfinite(r.u_ideal) | (np.abs(r.u_ideal) > lim)
        ax.plot(r.t, np.clip(np.nan_to_num(r.u_ideal, posinf=lim, neginf=-lim), -lim, lim), color="tab:blue",
                label="ideal u (clipped)")
        ax.plot(r.t[big], np.sign(r.u_ideal[big]) * lim, "k^", ms=3, label="|u| > plot range (singular)")
        ax.plot(r.t, r.u_shaped, color="tab:orange", label="shaped u")
        for b in (-u_bound, u_bound):
            ax.axhline(b, color="k", ls="--", lw=0.8)
        ax.set(title=f"{r.law.value}: input (eq. tracking_u_motiv), bounds ±{u_bound:g}", xlabel="t", ylabel="u")
        ax.set_ylim(-1.1 * lim, 1.1 * lim)
        ax.legend(fontsize=7, loc="lower right")
    return fig


def fig_closed_loop(rows: list[CaseRun], title: str) -> Figure:
    """Fig. dc_exp_cases (simulated): i, V, e_omega, e_F and omega/F tracking over one measured period."""
    fig = _figure(13.0, 8.0)
    axes = fig.subplots(4, 2, sharex=True)
    left = (("current", "I [A]"), ("voltage", "V [V]"), ("speed_error", r"$e_\omega$ [rad/s]"),
            ("thrust_error", "$e_F$ [N]"))
    for c, row in enumerate(rows):
        run, k0 = row.run, row.run.t >= row.period - 1e-12
        k = k0 & (run.t <= 2.0 * row.period + 1e-12)
        phase = run.t[k] / row.period
        for r, (name, lab) in enumerate(left):
            source = row if name.endswith("_error") else run  # errors against the row's target (desired)
            axes[r, 0].plot(phase, getattr(source, name)[k], color=COLORS[c], lw=0.9, label=row.label)
            axes[r, 0].set_ylabel(lab)
        for r, (target, act, lab) in enumerate(((row.target[1], "omega", r"$\omega$ [rad/s]"),
                                                  (row.target[0], "thrust", "F [N]"))):
            ax = axes[2 * r, 1]
            ax.plot(phase, target[k], "--", color=COLORS[c], lw=0.9)
            ax.plot(phase, getattr(run, act)[k], color=COLORS[c], lw=0.9, label=row.label)
            ax.set_ylabel(lab)
        axes[1, 1].plot(phase, np.abs(row.speed_error[k]), color=COLORS[c], lw=0.9)
        axes[3, 1].plot(phase, np.abs(row.thrust_error[k]), color=COLORS[c], lw=0.9)
    axes[1, 1].set(ylabel=r"$|e_\omega|$ [rad/s]", yscale="log")
    axes[3, 1].set(ylabel="$|e_F|$ [N]", yscale="log")
    axes[0, 0].legend(fontsize=8)
    axes[0, 1].legend(fontsize=8)
    for ax in axes[-1]:
        ax.set_xlabel("t / T (second period; dashed: what the row is scored against, the desired profile)")
    fig.suptitle(title)
    return fig
