"""``thrustshape design-experiment``: the excitation that settles an ambiguous diagnosis (over
:mod:`ocp.identify.design`; the log options and the diagnosis are those of :mod:`clients.cli.model`)."""

from __future__ import annotations

import argparse
import contextlib
import json
import sys
from typing import TYPE_CHECKING, Any

from clients.cli.help import STDIO, add_command, write_text
from clients.cli.io import fmt_number as _g
from clients.cli.io import print_json
from clients.cli.model import (
    _LOG_DESCRIPTION,
    _annotate,
    _diagnose_args,
    _diagnose_fields,
    _diagnose_options,
    _load_log,
    _log_args,
    _Progress,
    _upload,
)
from clients.cli.remote import client
from ocp.errors import ParameterError, ThrustshapeError

if TYPE_CHECKING:
    from ocp.identify import DiagnoseOptions


def register(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "design-experiment", summary="propose the experiment that settles an ambiguous diagnosis",
                    description="Diagnoses the log, then, when explanations tie (ambiguous) or an effect cannot "
                                "show in it\n(no reversal, no low speed, one speed), optimises candidate "
                                "excitations within the limits\n(slow reversals, a speed triangle, dwells at "
                                "several speeds, a chirp), simulates every rival\nexplanation under each and "
                                "writes the mission that separates them best, with the expected\nseparation "
                                "(z, in noise standard deviations; 'thrustshape optimize' runs it).\n"
                                + _LOG_DESCRIPTION,
                    examples=["thrustshape design-experiment rig.csv --params paper-rig --voltage 12 --current 2 "
                              "--out mission.json",
                              "thrustshape optimize mission.json --out experiment.csv   # play its voltage column"],
                    lists=("presets", "effects"))
    _log_args(p)
    _diagnose_args(p)
    p.add_argument("--voltage", type=float, default=None, help="voltage limit [V] (default: the log's peak |V|)")
    p.add_argument("--current", type=float, default=None, help="current limit [A] (default: the log's peak |i|)")
    p.add_argument("--duration", type=float, default=None,
                   help="experiment length [s] (default: 60 mechanical time constants, within 2..20 s)")
    p.add_argument("--rival", action="append", default=None, metavar="ITEMS",
                   help="a rival explanation, comma-separated effects or param:<key> (repeat; default: from the "
                        "diagnosis)")
    p.add_argument("--out", default=None, help="write the proposed mission (JSON) here ('-': stdout)")
    p.set_defaults(func=cmd_design)


def _rivals(args: argparse.Namespace) -> list[list[str]] | None:
    if not args.rival:
        return None
    sets = [[n.strip() for n in r.split(",") if n.strip()] for r in args.rival]
    if len(sets) < 2 or not all(sets):
        raise ParameterError("--rival", "give at least two non-empty rival explanations (repeat --rival)")
    from ocp.identify.candidates import candidate

    for name in (n for r in sets for n in r):
        try:
            candidate(name)
        except ThrustshapeError as exc:
            raise ParameterError("--rival", f"{name!r}: {exc.reason}") from None
    return sets


def cmd_design(args: argparse.Namespace) -> int:
    opts = _diagnose_options(args)
    fields = {"voltage": args.voltage, "current": args.current, "duration_s": args.duration, "rivals": _rivals(args)}
    if args.server:
        with client(args) as c, _Progress("design") as bar:
            job = c.submit_model_check("design", **_upload(args), **_diagnose_fields(args), **fields)
            d = c.wait_model_check(job["id"], on_progress=bar.update)
    else:
        d = _design_here(args, opts, fields)
    if args.out and d.get("mission") is not None:
        write_text(json.dumps(d["mission"], indent=2, allow_nan=False) + "\n", args.out)
    # with --out - the mission is stdout: the summary goes to stderr
    with contextlib.redirect_stdout(sys.stderr) if args.out == STDIO else contextlib.nullcontext():
        if args.json:
            print_json(d)
        else:
            _print_design(d, args.out)
    return 0


def _design_here(args: argparse.Namespace, opts: DiagnoseOptions, fields: dict[str, Any]) -> dict[str, Any]:
    from pydantic import ValidationError

    from ocp.identify import diagnose
    from ocp.identify.design import DesignOptions, design
    from ocp.model.effects import load_plant

    try:
        dopt = DesignOptions(**{**fields, "rivals": None if fields["rivals"] is None else
                                tuple(tuple(r) for r in fields["rivals"])})
    except ValidationError as exc:
        err = exc.errors()[0]
        raise ParameterError(f"--{str(err['loc'][0]).replace('_s', '').replace('_', '-')}", str(err["msg"])) from None
    log = _load_log(args)
    plant = load_plant(args.params)
    with _Progress("design") as bar:
        res = diagnose(plant, log, opts, progress=lambda f: bar.update(0.3 * f))
        out = design(plant, log, res, dopt, progress=lambda f: bar.update(0.3 + 0.7 * f)).to_dict()
    out["diagnosis"] = _annotate(res.to_dict(), log)
    return out


def _print_design(d: dict[str, Any], out: str | None) -> None:
    diag = d["diagnosis"]
    print("diagnosis: " + ("nothing missing" if not diag["verdict"] else ", ".join(diag["verdict"]))
          + (" (ambiguous)" if diag.get("ambiguous") else ""))
    for r in d["reasons"]:
        print(f"  why an experiment: {r}")
    if not d["needed"]:
        print(d["message"])
        return
    errors = d.get("current_log_errors") or {}
    print("rivals: " + " | ".join(r["name"] + (f" (misses this log by {_g(errors[r['name']], '.3g')} noise units)"
                                              if errors.get(r["name"]) is not None else "") for r in d["rivals"]))
    print("candidates (smallest separation over rival pairs, z in noise standard deviations):")
    for c in d["candidates"]:
        z = c["separation"] or c["raw_separation"]
        worst = min(z.values()) if z else None
        label = "z" if c["separation"] else "z before refit"
        print(f"  {c['name']:22s} {label} {_g(worst, '.3g'):>8s}  {c['note'] if not c['runnable'] else ''}")
    ch = d["chosen"]
    if ch is None:
        print(d["message"])
        return
    print(f"proposed: {ch['name']}: {ch['description']}")
    for pair, z in ch["separation"].items():
        print(f"  {pair:44s} z {_g(z, '.3g'):>8s}  (this log: {_g(d['current_log_separation'].get(pair), '.3g')})")
    v, lim = d["verification"], d["verification"]["limits"]
    print(f"  optimised within the limits: peak {_g(v['max_abs_current'], '.3g')} A of {_g(lim['current'], '.3g')}, "
          f"{_g(v['max_abs_voltage'], '.3g')} V of {_g(lim['voltage'], '.3g')}; {_g(v['duration_s'], '.3g')} s")
    print(d["message"])
    if out and out != STDIO:
        print(f"mission written to {out}: 'thrustshape optimize {out} --out experiment.csv' gives the voltage to play")
