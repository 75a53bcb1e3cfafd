"""Self-contained HTML report of a point-by-point check (:class:`~ocp.identify.steady.PointCheck`):
which equations were checked and which could not be (and why), what the reader did, the residuals by
direction, the direction maps, and one figure per checked equation (measured and model against speed)."""

from __future__ import annotations

import base64
import html
import json

import numpy as np

from ocp.identify.equations import UNITS, residuals
from ocp.identify.steady import PointCheck, directions
from ocp.logs import Log
from ocp.model.plant import DCMotorPlant


def _figure(plant: DCMotorPlant, log: Log, eqs: tuple[str, ...]) -> bytes:
    from ocp.identify.report import _png, _subplots

    res = residuals(plant, log, eqs)
    fig, axes = _subplots(len(eqs), 1, figsize=(8, 2.6 * len(eqs)), squeeze=False)
    for ax, eq in zip(axes[:, 0], eqs, strict=True):
        for name, mask in directions(log).items():
            if mask.any():
                ax.plot(log.omega[mask], res[eq][mask], ".", ms=4, label=name)
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.set_ylabel(f"{eq} residual [{UNITS[eq]}]", fontsize=8)
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("omega [rad/s]")
    fig.tight_layout()
    return bytes(_png(fig))


def points_html(result: PointCheck, log: Log, plant: DCMotorPlant, title: str = "thrustshape model check") -> str:
    """The report page (one file, the figure embedded as a data URI)."""
    eqs = tuple(e.name for e in result.equations if e.checked)
    rows = "".join(f"<tr><td>{html.escape(e.name)}</td><td>{'checked' if e.checked else 'not checked'}</td>"
                   f"<td>{html.escape(e.how)}</td></tr>" for e in result.equations)
    img = ""
    if eqs and log.n:
        src = base64.b64encode(_figure(plant, log, eqs)).decode()
        img = f'<img alt="residuals" src="data:image/png;base64,{src}">'
    notes = "".join(f"<li>{html.escape(n)}</li>" for n in result.notes)
    detail = html.escape(json.dumps({"breakdown": result.breakdown, "maps": result.maps, "drive": result.drive,
                                     "rms": result.rms}, indent=1, default=lambda v: None))
    return (f"<!DOCTYPE html><html><head><meta charset='utf-8'><title>{html.escape(title)}</title>"
            "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse;font-size:12px}"
            "td,th{border:1px solid #ccc;padding:2px 6px}</style></head><body>"
            f"<h1>{html.escape(title)}</h1><p>log: {html.escape(log.source)}, {log.n} rows ({log.kind.value}), "
            f"checked point by point (no simulation)</p><h2>Equations</h2><table><tr><th>equation</th><th>status</th>"
            f"<th>uses / why not</th></tr>{rows}</table><h2>How the log was read</h2><ul>{notes}</ul>"
            f"<h2>By direction</h2><pre>{detail}</pre><h2>Residuals against speed</h2>{img}"
            f"<p>{int(np.sum(log.omega == 0))} rows at rest.</p></body></html>")
