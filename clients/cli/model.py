"""Model-check commands: ``check``, ``diagnose``, ``fit`` (thin layer over :mod:`ocp.identify`)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from clients.cli.io import print_json
from ocp.effects import load_plant
from ocp.errors import LogError, ParameterError
from ocp.identify import CheckOptions, DiagnoseOptions, FitOptions, check, diagnose, fit
from ocp.identify.report import write_report
from ocp.logs import Log, LogKind, read_log


def _log_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("log", help="CSV/Parquet log (t, voltage, current, omega/theta, thrust; SI) or a Tyto export")
    p.add_argument("--params", required=True, help="parameter file (JSON/YAML, may hold 'effects') or preset name")
    p.add_argument("--columns", default=None,
                   help='column map as JSON, e.g. \'{"omega": {"column": "speed", "unit": "rpm"}}\'')
    p.add_argument("--steady-state", action="store_true", help="the log is a steady-state sweep (one row per point)")
    p.add_argument("--json", action="store_true", help="machine-readable output")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check", help="compare the model with a measured log: where does it fail?")
    _log_args(p)
    p.add_argument("--report", default=None, help="write a self-contained HTML report here")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("diagnose", help="rank candidate effects by held-out error reduction")
    _log_args(p)
    p.add_argument("--max-effects", type=int, default=3, help="at most this many effects in the verdict")
    p.add_argument("--no-corrections", action="store_true", help="do not try corrections of the nominal constants")
    p.set_defaults(func=cmd_diagnose)

    p = sub.add_parser("fit", help="add named effects, refit, write a calibrated parameter file")
    _log_args(p)
    p.add_argument("--effects", required=True, help="comma-separated effect names (or param:<key> corrections)")
    p.add_argument("--out", default=None, help="write the calibrated parameter file (JSON) here")
    p.add_argument("--no-refine", action="store_true", help="equation-error fit only (skip free-run refinement)")
    p.set_defaults(func=cmd_fit)


def _load_log(args: argparse.Namespace) -> Log:
    columns: Any = None
    if args.columns is not None:
        try:
            columns = json.loads(args.columns)
        except json.JSONDecodeError as exc:
            raise LogError("--columns", f"not valid JSON: {exc}") from None
        if not isinstance(columns, dict):
            raise LogError("--columns", "must be a JSON object {quantity: {column, unit}}")
    kind = LogKind.STEADY_STATE if args.steady_state else LogKind.TIME_SERIES
    return read_log(args.log, columns, kind)


def cmd_check(args: argparse.Namespace) -> int:
    log = _load_log(args)
    res = check(load_plant(args.params), log, CheckOptions())
    if args.report:
        write_report(res, log, args.report)
    if args.json:
        print_json(res.to_dict())
        return 0
    print("free run (model simulated under the measured voltage) RMS error:")
    for ch, v in res.free_run_rms.items():
        print(f"  {ch:8s} {v:.4g}   (sensor noise ~{res.noise[ch]:.3g})")
    print("one-step equation residual RMS:")
    for eq, v in res.one_step_rms.items():
        print(f"  {eq:10s} {v:.4g}")
    return 0


def cmd_diagnose(args: argparse.Namespace) -> int:
    log = _load_log(args)
    if args.max_effects < 1:
        raise ParameterError("--max-effects", "must be >= 1")
    opt = DiagnoseOptions(max_effects=args.max_effects, include_params=not args.no_corrections)
    res = diagnose(load_plant(args.params), log, opt)
    if args.json:
        print_json(res.to_dict())
        return 0
    print("nothing missing" if not res.verdict else "missing: " + ", ".join(res.verdict))
    for text in res.explanations:
        print(f"  {text}")
    print("ranking (held-out error reduction):")
    for e in res.ranking[:8]:
        print(f"  {e.name:18s} {100 * e.improvement:6.1f} %  {'significant' if e.significant else ''}")
    return 0


def cmd_fit(args: argparse.Namespace) -> int:
    names = [n.strip() for n in args.effects.split(",") if n.strip()]
    if not names:
        raise ParameterError("--effects", "give at least one effect name")
    log = _load_log(args)
    res = fit(load_plant(args.params), log, names, FitOptions(refine=not args.no_refine))
    if args.out:
        res.write(args.out)
    if args.json:
        print_json(res.to_dict())
        return 0
    print(f"fitted ({res.stage} stage):")
    for n, v, s in zip(res.names, res.values, res.stderr, strict=True):
        print(f"  {n:28s} {v:.5g}  +- {s:.2g}")
    print("free-run RMS error   before -> after:")
    for ch in res.before:
        print(f"  {ch:8s} {res.before[ch]:.4g} -> {res.after[ch]:.4g}")
    return 0
