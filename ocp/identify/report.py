"""PNG figures and a self-contained HTML report of a :class:`~ocp.identify.check.CheckResult`.

Figures are :class:`matplotlib.figure.Figure` objects drawn on their own Agg canvas: the caller's
pyplot backend and figure list are never touched. The HTML embeds the PNGs as base64 data URIs,
so the report is one file with no external resources.
"""

from __future__ import annotations

import base64
import html
import io
import json
from pathlib import Path
from typing import Any

import numpy as np

from ocp.identify.check import CheckResult
from ocp.identify.predict import CHANNEL_UNITS, CHANNELS, EQUATION_UNITS, EQUATIONS
from ocp.identify.steady import PointCheck
from ocp.logs import Log
from ocp.model.plant import DCMotorPlant


def _subplots(nrows: int, ncols: int, figsize: tuple[float, float], **kw: Any) -> tuple[Any, Any]:
    """``pyplot.subplots`` without pyplot: a Figure on its own Agg canvas (no global backend switch)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig, fig.subplots(nrows, ncols, **kw)


def _png(fig: Any) -> bytes:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    return buf.getvalue()


def figures(result: CheckResult, log: Log) -> dict[str, bytes]:
    """PNG bytes by name: ``free_run``, ``one_step``, ``breakdown``, ``correlation``."""
    out: dict[str, bytes] = {}
    fr, res = result.free, result.residuals
    fig, axes = _subplots(3, 1, (9, 7), sharex=True)
    for ax, ch in zip(axes, CHANNELS, strict=True):
        ax.plot(log.t, getattr(log, ch), lw=0.6, color="0.5", label="measured")
        ax.plot(log.t[fr.idx], fr.channel(ch), lw=0.8, label="model (free run)")
        ax.set_ylabel(f"{ch} [{CHANNEL_UNITS[ch]}]")
    axes[0].legend(loc="upper right")
    axes[-1].set_xlabel("t [s]")
    out["free_run"] = _png(fig)
    fig, axes = _subplots(3, 1, (9, 7), sharex=True)
    for ax, eq in zip(axes, EQUATIONS, strict=True):
        ax.plot(log.t[res.idx], res.equation(eq), lw=0.5)
        ax.set_ylabel(f"{eq} [{EQUATION_UNITS[eq]}]")
    axes[0].set_title("one-step equation residuals (measured - model)")
    axes[-1].set_xlabel("t [s]")
    out["one_step"] = _png(fig)
    groups = list(result.breakdown)
    fig, axes = _subplots(len(groups), 1, (9, 2.2 * len(groups)))
    for ax, g in zip(np.atleast_1d(axes), groups, strict=True):
        labels = list(result.breakdown[g])
        vals = [result.breakdown[g][lb]["one_step_mean.mechanical"] or 0.0 for lb in labels]
        ax.bar(range(len(labels)), vals)
        ax.set_xticks(range(len(labels)), labels, fontsize=7)
        ax.set_ylabel("mean torque\nresidual [N m]", fontsize=8)
        ax.set_title(g, fontsize=9)
    fig.tight_layout()
    out["breakdown"] = _png(fig)
    corr = result.correlation
    fig, axes = _subplots(1, 3, (10, 3))
    for ax, key in zip(axes, ("acf", "xcorr_voltage", "xcorr_omega"), strict=True):
        for eq in EQUATIONS:
            ax.plot(corr["lags"], [v or 0.0 for v in corr[key][eq]], lw=0.8, label=eq)
        ax.axhspan(-corr["band"], corr["band"], color="0.85")
        ax.set_title(key, fontsize=9)
        ax.set_xlabel("lag [samples]")
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    out["correlation"] = _png(fig)
    return out


def _table(rows: dict[str, dict[str, object]]) -> str:
    cols = list(next(iter(rows.values())).keys()) if rows else []
    head = "".join(f"<th>{html.escape(c)}</th>" for c in ["bin", *cols])
    body = "".join("<tr><td>" + html.escape(lb) + "</td>" + "".join(
        f"<td>{v:.4g}</td>" if isinstance(v, float) else f"<td>{html.escape(str(v))}</td>" for v in r.values())
        + "</tr>" for lb, r in rows.items())
    return f"<table><tr>{head}</tr>{body}</table>"


def html_report(result: CheckResult | PointCheck, log: Log, title: str = "thrustshape model check",
                plant: DCMotorPlant | None = None) -> str:
    """A self-contained HTML page: summary, breakdown tables, embedded figures."""
    if isinstance(result, PointCheck):  # issue #13: a point-by-point check has its own page
        from ocp.identify.points_report import points_html

        if plant is None:
            raise TypeError("a point-by-point report needs the plant")
        return points_html(result, log, plant, title)
    figs = figures(result, log)
    imgs = "".join(f'<h3>{html.escape(k)}</h3><img alt="{html.escape(k)}" src="data:image/png;base64,'
                   f'{base64.b64encode(v).decode()}">' for k, v in figs.items())
    tables = "".join(f"<h3>{html.escape(g)}</h3>{_table(b)}" for g, b in result.breakdown.items())
    shown = ("alignment", "free_run", "one_step", "noise")
    summary = html.escape(json.dumps({k: v for k, v in result.to_dict().items() if k in shown}, indent=1))
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse;font-size:12px}"
            "td,th{border:1px solid #ccc;padding:2px 6px}</style></head><body>"
            f"<h1>{html.escape(title)}</h1><p>log: {html.escape(log.source)}, {log.n} samples ({log.kind.value})</p>"
            f"<h2>Summary</h2><pre>{summary}</pre><h2>Where it fails</h2>{tables}<h2>Figures</h2>{imgs}"
            "</body></html>")


def write_report(result: CheckResult | PointCheck, log: Log, path: str | Path,
                 plant: DCMotorPlant | None = None) -> None:
    Path(path).write_text(html_report(result, log, plant=plant), encoding="utf-8")
