"""Regenerate every gallery figure into a directory, with ``index.html`` and the closed-loop table.

Output (in ``out``): ``<figure>.png`` and ``<figure>.svg`` per figure, ``closed_loop_table.json`` and
``closed_loop_table.csv`` (simulated vs paper), ``index.html`` linking everything.
"""

from __future__ import annotations

import csv
import html
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ocp.errors import MissionError
from ocp.gallery import figures as figs
from ocp.gallery.experiment import METRIC_COLUMNS, ExperimentSetup, run_experiment, table_rows
from ocp.gallery.interaction import InteractionSetup, Law, interaction_reference
from ocp.params import load_params

#: the normal-form figures use the interaction example's k and these input bounds (paper: 0 < u_low < u_high)
PHASE_U_LOW = 1.0
PHASE_U_HIGH = 2.0


@dataclass(frozen=True)
class GalleryOutput:
    """What :func:`build_gallery` wrote.

    Attributes:
        out: the directory
        figures: figure name -> (caption, [png, svg] file names)
        table: rows of the closed-loop table (see :func:`ocp.gallery.experiment.table_rows`)
        optimised_note: why optimised rows are missing or fell back ("" when present and optimised)
    """

    out: Path
    figures: dict[str, tuple[str, list[str]]] = field(default_factory=dict)
    table: list[dict[str, Any]] = field(default_factory=list)
    optimised_note: str = ""


def build_gallery(out: Path | str, interaction: InteractionSetup | None = None,
                  experiment: ExperimentSetup | None = None) -> GalleryOutput:
    """Regenerate all figures and the table into ``out`` (created if missing)."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise MissionError("out", f"{out} exists and is not a directory")
    out.mkdir(parents=True, exist_ok=True)
    inter = InteractionSetup() if interaction is None else interaction
    exp = ExperimentSetup() if experiment is None else experiment
    params = load_params(exp.params)
    refs = [interaction_reference(law, inter) for law in Law]
    rows, note = run_experiment(exp)
    paper_rows = [r for r in rows if r.label.startswith("Case")]
    opt_rows = [r for r in rows if not r.label.startswith("Case")]
    made = [
        ("f2_map", "Normal-form drift and input gain vs normalised thrust (Fig. f2_map).",
         figs.fig_f2_map(inter.k)),
        ("trjphase",
         f"Feasibility set S for u in [-{PHASE_U_LOW:g}, {PHASE_U_HIGH:g}], k = {inter.k:g} (Fig. trjphase).",
         figs.fig_trjphase(inter.k, PHASE_U_LOW, PHASE_U_HIGH)),
        ("dc_reference_cases", "Ideal voltage, current, speed, thrust for six crossing orders on the paper rig "
         "(Fig. dc_reference_cases); Case orders p = " + ", ".join(map(str, figs.CASE_ORDERS)) + ".",
         figs.fig_dc_reference_cases(params)),
        ("interaction", "Impedance and admittance references (Section IV-B, Fig. admit_exa): the ideal input is "
         "singular at the linear crossings; the shaped (actuator-aware) references keep it within bounds.",
         figs.fig_interaction(refs, inter.u_bound)),
        ("closed_loop_cases", "Closed-loop simulation of the Section V rig, Cases 1, 4, 5 (Fig. dc_exp_cases).",
         figs.fig_closed_loop(paper_rows, "Section V rig, simulated: Case 1 (A sin), 4 (A sin^5), 5 (A sin^7)")),
    ]
    if opt_rows:
        made.append(("closed_loop_optimised", f"Case 1 vs {opt_rows[0].note.split(',')[0]} for the same mission "
                     f"(rows '{opt_rows[0].label}'), without and with its voltage feedforward.",
                     figs.fig_closed_loop([paper_rows[0], *opt_rows], f"Case 1 vs {opt_rows[0].label} reference")))
    files = {name: (caption, figs.save(fig, out, name)) for name, caption, fig in made}
    table = table_rows(rows)
    _write_table(out, table)
    result = GalleryOutput(out=out, figures=files, table=table, optimised_note="" if opt_rows and not note else note)
    (out / "index.html").write_text(_index_html(result, exp), encoding="utf-8")
    return result


def _write_table(out: Path, table: list[dict[str, Any]]) -> None:
    (out / "closed_loop_table.json").write_text(json.dumps(table, indent=1, allow_nan=False), encoding="utf-8")
    with (out / "closed_loop_table.csv").open("w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["label", "source", *[k for k, _ in METRIC_COLUMNS]])
        for row in table:
            w.writerow([row["label"], "simulated", *[repr(row["simulated"][k]) for k, _ in METRIC_COLUMNS]])
            if row["paper"]:
                w.writerow([row["label"], "paper", *["" if row["paper"][k] is None else repr(row["paper"][k])
                                                     for k, _ in METRIC_COLUMNS]])


def _fmt(v: float | None) -> str:
    return "–" if v is None else f"{v:.3g}"


def _table_html(table: list[dict[str, Any]]) -> str:
    head = "".join(f"<th>{html.escape(lab)}</th>" for _, lab in METRIC_COLUMNS)
    body = []
    for row in table:
        sim = "".join(f"<td>{_fmt(row['simulated'][k])}</td>" for k, _ in METRIC_COLUMNS)
        ref = f"{html.escape(row['note'])}, T = {row['period_s']:.3g} s, A = {row['amplitude_N']:.3g} N"
        body.append(f"<tr><td>{html.escape(row['label'])}</td><td>simulated</td>{sim}<td>{ref}</td></tr>")
        if row["paper"]:
            pap = "".join(f"<td>{_fmt(row['paper'][k])}</td>" for k, _ in METRIC_COLUMNS)
            body.append(f"<tr class='paper'><td>{html.escape(row['label'])}</td><td>paper</td>{pap}"
                        "<td>measured</td></tr>")
    return (f"<table><tr><th>row</th><th>source</th>{head}<th>reference</th></tr>{''.join(body)}</table>")


def _index_html(g: GalleryOutput, exp: ExperimentSetup) -> str:
    items = []
    for name, (caption, files) in g.figures.items():
        png, svg = files
        items.append(f"<figure id='{name}'><a href='{svg}'><img src='{png}' alt='{name}'></a>"
                     f"<figcaption><b>{name}</b>: {html.escape(caption)} [<a href='{png}'>PNG</a> | "
                     f"<a href='{svg}'>SVG</a>]</figcaption></figure>")
    opt = (f"<p><b>Optimised rows:</b> {html.escape(g.optimised_note)}</p>" if g.optimised_note else "")
    return f"""<!doctype html>
<html lang="en"><head><meta charset="utf-8"><title>thrustshape gallery</title>
<style>body{{font-family:sans-serif;max-width:1200px;margin:auto}} img{{max-width:100%}}
table{{border-collapse:collapse;font-size:90%}} td,th{{border:1px solid #aaa;padding:3px 6px}}
tr.paper{{background:#eef}}</style></head><body>
<h1>thrustshape gallery: the seed paper, regenerated</h1>
<p>Every figure below is recomputed by <code>thrustshape gallery</code> from the project's own code.</p>
<h2>Closed-loop table (Section V rig, simulated vs the paper's measurements)</h2>
<p>Speeds in rad/s: the paper's "Hz" is read as rad/s, as in the <code>paper-rig</code> preset. The rig's electrical
constants are assumed, so absolute numbers differ; the trend is the test: Case 1 clearly worst, Cases 4 and 5 similar.
Metrics over periods {exp.skip_periods + 1}..{exp.periods} of each run; "local" = within ±50 ms of a reversal.
Controller gains read as counts per SI unit (see <code>ocp/closed_loop.py</code>).</p>
{_table_html(g.table)}
{opt}
<h2>Figures</h2>
{''.join(items)}
<p>Files: <a href="closed_loop_table.json">closed_loop_table.json</a>,
<a href="closed_loop_table.csv">closed_loop_table.csv</a></p>
</body></html>
"""


def summary_lines(g: GalleryOutput) -> list[str]:
    """Human-readable summary of a build: where the files are and the closed-loop table."""
    lines = [f"gallery written to {g.out}/index.html ({len(g.figures)} figures, PNG + SVG)"]
    lines.append(f"{'row':<16}{'source':<11}" + "".join(f"{lab:>22}" for _, lab in METRIC_COLUMNS))
    for row in g.table:
        for src in ("simulated", "paper"):
            vals = row[src]
            if vals:
                cells = "".join(f"{_fmt(vals[k]):>22}" for k, _ in METRIC_COLUMNS)
                lines.append(f"{row['label']:<16}{src:<11}{cells}")
    if g.optimised_note:
        lines.append(f"optimised rows: {g.optimised_note}")
    return lines
