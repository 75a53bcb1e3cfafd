"""Model-check commands: ``check``, ``diagnose``, ``fit`` (thin layer over :mod:`ocp.identify`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from pydantic import ValidationError

from clients.cli.io import fmt_number as _g
from clients.cli.io import print_json
from clients.cli.remote import add_server_args, client, params_for_server
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
    add_server_args(p)


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("check", help="compare the model with a measured log: where does it fail?")
    _log_args(p)
    p.add_argument("--report", default=None, help="write a self-contained HTML report here")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("diagnose", help="rank candidate effects by held-out error reduction")
    _log_args(p)
    p.add_argument("--max-effects", type=int, default=3, help="at most this many effects in the verdict")
    p.add_argument("--no-corrections", action="store_true", help="never name a constant wrong (calibrate only)")
    p.add_argument("--tolerance", type=float, default=0.10,
                   help="a constant is named wrong only beyond this relative error (default 0.10 = 10 %%)")
    p.add_argument("--max-logging-skew", type=float, default=2.0,
                   help="command-to-sensor lag [samples] that logging conventions explain (beyond: input_delay)")
    p.set_defaults(func=cmd_diagnose)

    p = sub.add_parser("fit", help="add named effects, refit, write a calibrated parameter file")
    _log_args(p)
    p.add_argument("--effects", required=True, help="comma-separated effect names (or param:<key> corrections)")
    p.add_argument("--out", default=None, help="write the calibrated parameter file (JSON) here")
    p.add_argument("--no-refine", action="store_true", help="equation-error fit only (skip free-run refinement)")
    p.set_defaults(func=cmd_fit)


def _columns(args: argparse.Namespace) -> Any:
    if args.columns is None:
        return None
    try:
        columns = json.loads(args.columns)
    except json.JSONDecodeError as exc:
        raise LogError("--columns", f"not valid JSON: {exc}") from None
    if not isinstance(columns, dict):
        raise LogError("--columns", "must be a JSON object {quantity: {column, unit}}")
    return columns


def _load_log(args: argparse.Namespace) -> Log:
    kind = LogKind.STEADY_STATE if args.steady_state else LogKind.TIME_SERIES
    return read_log(args.log, _columns(args), kind)


def _upload(args: argparse.Namespace) -> dict[str, Any]:
    """What ``--server`` sends: the log file's bytes, the parameters (a local file read here), the column map."""
    if not Path(args.log).is_file():
        raise LogError(str(args.log), "no such file")
    return {"log": args.log, "params": params_for_server(args.params), "columns": _columns(args),
            "steady_state": args.steady_state}


def cmd_check(args: argparse.Namespace) -> int:
    if args.server:
        with client(args) as c:
            d = c.check(**_upload(args))
            if args.report:
                Path(args.report).write_text(c.check_report(**_upload(args)), encoding="utf-8")
    else:
        log = _load_log(args)
        res = check(load_plant(args.params), log, CheckOptions())
        if args.report:
            write_report(res, log, args.report)
        d = res.to_dict()
    if args.json:
        print_json(d)
        return 0
    print("free run (model simulated under the measured voltage) RMS error:")
    for ch, v in d["free_run"]["rms"].items():
        print(f"  {ch:8s} {_g(v, '.4g')}   (sensor noise ~{_g(d['noise'][ch], '.3g')})")
    print("one-step equation residual RMS:")
    for eq, v in d["one_step"]["rms"].items():
        print(f"  {eq:10s} {_g(v, '.4g')}")
    return 0


def cmd_diagnose(args: argparse.Namespace) -> int:
    if args.max_effects < 1:
        raise ParameterError("--max-effects", "must be >= 1")
    if args.server:
        with client(args) as c:
            d = c.diagnose(**_upload(args), max_effects=args.max_effects, corrections=not args.no_corrections)
    else:
        log = _load_log(args)
        opt = _diagnose_options(args)
        with _Progress("diagnose") as bar:
            d = diagnose(load_plant(args.params), log, opt, progress=bar.update).to_dict()
    if args.json:
        print_json(d)
        return 0
    _print_diagnosis(d)
    return 0


def _diagnose_options(args: argparse.Namespace) -> DiagnoseOptions:
    try:
        return DiagnoseOptions(max_effects=args.max_effects, include_params=not args.no_corrections,
                               tolerance=args.tolerance, max_logging_skew=args.max_logging_skew)
    except ValidationError as exc:
        err = exc.errors()[0]
        raise ParameterError(f"--{str(err['loc'][0]).replace('_', '-')}", str(err["msg"])) from None


class _Progress:
    """A one-line progress bar on stderr, drawn only when stderr is a terminal."""

    def __init__(self, label: str) -> None:
        self.label, self.tty = label, sys.stderr.isatty()

    def __enter__(self) -> _Progress:
        return self

    def update(self, fraction: float) -> None:
        if self.tty:
            n = int(30 * min(max(fraction, 0.0), 1.0))
            sys.stderr.write(f"\r{self.label} [{'#' * n}{'.' * (30 - n)}] {100 * fraction:3.0f} %")
            sys.stderr.flush()

    def __exit__(self, *exc: object) -> None:
        if self.tty:
            sys.stderr.write("\r" + " " * 50 + "\r")
            sys.stderr.flush()


def _print_diagnosis(d: dict[str, Any]) -> None:
    print("nothing missing" if not d["verdict"] else "missing: " + ", ".join(d["verdict"]))
    for text in d["explanations"]:
        print(f"  {text}")
    for a in d.get("ambiguous") or []:
        print(f"ambiguous: {a['adopted']} or {a['alternative']}: {a['reason']}")
    al = d.get("alignment")
    if al:
        print(f"alignment: command acts {_g(al['samples'], '.2f')} samples ({_g(1e3 * al['seconds'], '.3g')} ms) after "
              f"its row{' -> input_delay' if al['called_input_delay'] else ' (removed: logging convention)'}")
        print(f"  rule: {al['rule']}")
    cal = d.get("calibration") or {}
    if cal:
        print(f"calibration (refinements within {100 * d.get('tolerance', 0.1):.0f} % stay here; beyond it a constant "
              "is named in the verdict):")
        for k, c in cal.items():
            rel = 100 * c["relative"] if isinstance(c["relative"], int | float) else None
            print(f"  {k:6s} {_g(c['nominal'], '.4g'):>10s} -> {_g(c['fitted'], '.4g'):>10s} {c['unit']:16s} "
                  f"{_g(rel, '+6.1f')} %{'  NAMED' if c['named'] else ''}")
    ap = d.get("angle_periodic")
    if ap:
        print(f"angle-periodic torque: strongest at {ap['periods']} periods/rev, "
              f"amplitude {_g(ap['amplitude'], '.3g')} "
              f"N m (median over 1..64: {_g(ap['median_amplitude'], '.3g')} N m)")
    print("ranking (held-out error reduction):")
    for e in d["ranking"][:8]:
        imp = 100 * e["improvement"] if isinstance(e["improvement"], int | float) else None
        print(f"  {e['effect']:18s} {_g(imp, '6.1f'):>6s} %  {'significant' if e['significant'] else ''}")


def cmd_fit(args: argparse.Namespace) -> int:
    names = [n.strip() for n in args.effects.split(",") if n.strip()]
    if not names:
        raise ParameterError("--effects", "give at least one effect name")
    if args.server:
        with client(args) as c:
            d = c.fit(**_upload(args), effects=names, refine=not args.no_refine)
        if args.out:  # the same file FitResult.write makes
            Path(args.out).write_text(json.dumps(d["calibrated_params"], indent=2, allow_nan=False) + "\n",
                                      encoding="utf-8")
    else:
        log = _load_log(args)
        res = fit(load_plant(args.params), log, names, FitOptions(refine=not args.no_refine))
        if args.out:
            res.write(args.out)
        d = res.to_dict()
    if args.json:
        print_json(d)
        return 0
    print(f"fitted ({d['stage']} stage):")
    for n, p in d["parameters"].items():
        print(f"  {n:28s} {_g(p['value'], '.5g')}  +- {_g(p['stderr'], '.2g')}")
    print("free-run RMS error   before -> after:")
    for ch in d["rms_before"]:
        print(f"  {ch:8s} {_g(d['rms_before'][ch], '.4g')} -> {_g(d['rms_after'][ch], '.4g')}")
    return 0
