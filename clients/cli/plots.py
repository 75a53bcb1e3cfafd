"""``optimize --plot FILE``: the optimised reference drawn with matplotlib's object API (a
:class:`~matplotlib.figure.Figure` on the Agg canvas; the caller's pyplot backend is never touched)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from ocp.errors import MissionError

#: what ``--plot`` can write, by suffix
FORMATS = (".svg", ".png", ".pdf")

_PANELS = (("thrust", "thrust [N]"), ("omega", "speed [rad/s]"), ("current", "current [A]"),
           ("voltage", "voltage [V]"))


def check_plot_path(path: str) -> None:
    """Refuse an unknown format before any work starts (the error names ``--plot``)."""
    if Path(path).suffix.lower() not in FORMATS:
        raise MissionError("--plot", f"{path!r}: the file name must end in {', '.join(FORMATS)}")


def plot_reference(result: dict[str, Any], limits: dict[str, float | None], path: str) -> None:
    """Thrust (desired dashed vs optimised), speed, current and voltage of an ``optimize`` answer
    (``OptimizeResult.to_dict()``, local or from a server) with the current/voltage ``limits`` [A, V]
    dashed and each reversal marked; PNG, SVG or PDF by the suffix of ``path``."""
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(9, 9), layout="constrained")
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(_PANELS), 1, sharex=True)
    t = np.asarray(result["t"], float)
    for ax, (key, label) in zip(axes, _PANELS, strict=True):
        y = np.array([np.nan if v is None else v for v in result[key]], float)  # null: a non-finite sample
        ax.plot(t, y, lw=1.3, label="optimised" if key == "thrust" else None)
        bound = limits.get(key)
        if bound is not None:
            for sign in (1, -1):
                ax.axhline(sign * bound, color="tab:red", ls="--", lw=0.8)
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    desired = np.array([np.nan if v is None else v for v in result["thrust_desired"]], float)
    axes[0].plot(t, desired, "k--", lw=0.9, label="desired")
    for c in result.get("crossings") or []:
        axes[0].axvline(c["t"], color="0.6", lw=0.6)
        g = c.get("exponent")
        if isinstance(g, int | float):
            axes[0].annotate(f"g={g:.2f}", (c["t"], 0), fontsize=7, xytext=(3, 3), textcoords="offset points")
    axes[0].legend(fontsize=8)
    axes[-1].set_xlabel("t [s]")
    fig.suptitle(f"{result.get('name', 'mission')}: {result.get('source', '')} ({result.get('status', '')})")
    fig.savefig(path)
