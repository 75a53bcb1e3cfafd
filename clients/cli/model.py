"""Model-check commands: ``check``, ``diagnose``, ``fit`` (thin layer over :mod:`ocp.identify`)."""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

from clients.cli.answers import print_alignment, print_diagnosis, print_equations, print_points
from clients.cli.help import STDIO, add_command
from clients.cli.io import fmt_number as _g
from clients.cli.io import print_json
from clients.cli.remote import add_server_args, client, params_for_server
from ocp.errors import LogError, ParameterError

if TYPE_CHECKING:  # the core is imported inside the commands: `thrustshape --help` stays fast
    from pydantic import BaseModel

    from ocp.identify import DiagnoseOptions
    from ocp.logs import Log, ReadOptions

_O = TypeVar("_O", bound="BaseModel")

_LOG_DESCRIPTION = ("A log is CSV/Parquet/.xlsx/.mat with headers and units (Tyto/RCbenchmark exports, vendor "
                    "sweeps,\nor t, voltage, current, omega/theta, thrust in SI; --columns maps other names and "
                    "units),\na PX4 .ulg or an ArduPilot .bin flight log.")


def _log_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("log", help="log: CSV/Parquet/.xlsx/.mat (headers with units: Tyto/RCbenchmark exports, vendor "
                               "sweeps, or t, voltage, current, omega/theta, thrust in SI), PX4 .ulg, ArduPilot .bin "
                               "('-': stdin, CSV or Parquet)")
    p.add_argument("--params", required=True, help="parameter file (JSON/YAML, may hold 'effects') or preset name")
    p.add_argument("--columns", default=None,
                   help='column map as JSON, e.g. \'{"omega": {"column": "speed", "unit": "rpm"}}\'')
    p.add_argument("--steady-state", nargs="?", const="yes", default="auto", choices=("auto", "yes", "no"),
                   help="the log is a steady-state sweep (one row per point); default auto: detected where the "
                        "file makes it plain (no time column, monotone command)")
    p.add_argument("--pole-pairs", type=int, default=None, help="motor pole pairs, for electrical speed (eRPM)")
    p.add_argument("--neutral-us", type=float, default=1500.0,
                   help="ESC neutral pulse [us]; unsigned speed/thrust take sign(command - neutral) (default 1500)")
    p.add_argument("--throttle-range", default=None, metavar="MIN,MAX",
                   help="ESC pulse range [us] for the command fraction (default 1100,1900)")
    p.add_argument("--electrical", choices=("auto", "armature", "supply"), default="auto",
                   help="whose voltage/current the log holds (auto: the supply's when there is an ESC command)")
    p.add_argument("--motor", type=int, default=0, help="which motor/ESC of a flight log (default 0)")
    p.add_argument("--no-resample", action="store_true", help="refuse irregular timestamps instead of resampling")
    p.add_argument("--negate", action="append", choices=("voltage", "current", "omega", "thrust", "torque"),
                   help="a channel the log holds with the opposite sign to the model's (repeatable)")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    add_server_args(p)


def _read_fields(args: argparse.Namespace) -> dict[str, Any]:
    """The read options as the API's form fields (and :class:`ocp.logs.ReadOptions` fields after parsing)."""
    out: dict[str, Any] = {"pole_pairs": args.pole_pairs, "neutral_us": args.neutral_us,
                           "throttle_range_us": args.throttle_range, "electrical": args.electrical,
                           "motor": args.motor, "resample": "refuse" if args.no_resample else "auto",
                           "negate": ",".join(args.negate) if args.negate else None}
    return {k: v for k, v in out.items() if v is not None}


def _read_options(args: argparse.Namespace) -> ReadOptions:
    from pydantic import ValidationError

    from ocp.logs import ReadOptions

    fields = _read_fields(args)
    text = fields.pop("throttle_range_us", None)
    if text is not None:
        try:
            lo, hi = (float(v) for v in str(text).split(","))
        except ValueError:
            raise LogError("--throttle-range", f"{text!r} is not MIN,MAX in us (e.g. 1100,1900)") from None
        fields["throttle_range_us"] = (lo, hi)
    try:
        return ReadOptions(**fields)
    except ValidationError as exc:
        err = exc.errors()[0]
        raise LogError(f"--{str(err['loc'][0] if err['loc'] else 'options').replace('_', '-')}", err["msg"]) from None


def _steady(args: argparse.Namespace) -> bool | None:
    return None if args.steady_state == "auto" else args.steady_state == "yes"


def _annotate(d: dict[str, Any], log: Log) -> dict[str, Any]:
    from ocp.identify.equations import annotate

    return annotate(d, log)


def register(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "check", summary="compare the model with a measured log: where does it fail?",
                    description="Free-run error (the plant simulated under the measured voltage) and one-step "
                                "equation\nresiduals, broken down by direction, reversals, speed band, "
                                "acceleration and angle.\n" + _LOG_DESCRIPTION,
                    examples=["thrustshape check rig.csv --params paper-rig --report check.html",
                              "thrustshape check rig.csv --params examples/params.yaml --json"], lists=("presets",))
    _log_args(p)
    p.add_argument("--report", default=None, help="write a self-contained HTML report here")
    _skew_arg(p)
    p.set_defaults(func=cmd_check)

    p = add_command(sub, "diagnose", summary="rank candidate effects by held-out error reduction",
                    description="Fits every effect of the catalogue (and corrections param:<key> of the nominal "
                                "constants)\nand ranks them by held-out error reduction; clean data gives an "
                                "empty verdict.\n" + _LOG_DESCRIPTION,
                    examples=["thrustshape diagnose rig.csv --params paper-rig --json"], lists=("presets", "effects"))
    _log_args(p)
    _diagnose_args(p)
    p.set_defaults(func=cmd_diagnose)

    p = add_command(sub, "fit", summary="add named effects, refit, write a calibrated parameter file",
                    description="Adds the named effects to the model, refits them (and the constants named "
                                "param:<key>)\nand writes a calibrated parameter file that --params and "
                                "missions accept.\n" + _LOG_DESCRIPTION,
                    examples=["thrustshape fit rig.csv --params paper-rig --effects coulomb_friction "
                              "--out calibrated.json"], lists=("presets", "effects"))
    _log_args(p)
    p.add_argument("--effects", required=True, help="comma-separated effect names (or param:<key> corrections)")
    p.add_argument("--out", default=None, help="write the calibrated parameter file (JSON) here")
    p.add_argument("--no-refine", action="store_true", help="equation-error fit only (skip free-run refinement)")
    _skew_arg(p)
    p.set_defaults(func=cmd_fit)


def _diagnose_args(p: argparse.ArgumentParser) -> None:
    p.add_argument("--max-effects", type=int, default=3, help="at most this many effects in the verdict")
    p.add_argument("--no-corrections", action="store_true", help="never name a constant wrong (calibrate only)")
    p.add_argument("--tolerance", type=float, default=0.10,
                   help="a constant is named wrong only beyond this relative error (default 0.10 = 10 %%)")
    _skew_arg(p)


def _skew_arg(p: argparse.ArgumentParser) -> None:
    p.add_argument("--max-logging-skew", type=float, default=2.0,
                   help="command-to-sensor lag [samples] that logging conventions explain, removed first "
                        "(diagnose: beyond it, input_delay)")


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


def _stdin_log(args: argparse.Namespace) -> tuple[str, bytes]:
    """``(file name, bytes)`` of a log given as ``-``, read once (Parquet told apart by its magic bytes)."""
    if not hasattr(args, "_stdin_log"):
        data = sys.stdin.buffer.read()
        args._stdin_log = ("stdin.parquet" if data[:4] == b"PAR1" else "stdin.csv", data)
    return args._stdin_log


def _load_log(args: argparse.Namespace) -> Log:
    from ocp.logs import LogKind, read_log

    steady = _steady(args)
    kind = None if steady is None else (LogKind.STEADY_STATE if steady else LogKind.TIME_SERIES)
    if args.log != STDIO:
        return read_log(args.log, _columns(args), kind, options=_read_options(args))
    name, data = _stdin_log(args)
    with tempfile.TemporaryDirectory(prefix="thrustshape-") as tmp:  # the log readers take a path
        (path := Path(tmp) / name).write_bytes(data)
        return read_log(path, _columns(args), kind, options=_read_options(args))


def _upload(args: argparse.Namespace) -> dict[str, Any]:
    """What ``--server`` sends: the log file's bytes, the parameters (a local file read here), the column map."""
    if args.log == STDIO:
        log: Any = _stdin_log(args)
    elif not Path(args.log).is_file():
        raise LogError(str(args.log), "no such file")
    else:
        log = args.log
    _read_options(args)  # checked here, named by the CLI option
    return {"log": log, "params": params_for_server(args.params), "columns": _columns(args),
            "steady_state": _steady(args), "read": _read_fields(args)}


def cmd_check(args: argparse.Namespace) -> int:
    if args.server:
        with client(args) as c:
            d = _server_job(c, "check", args, max_logging_skew=args.max_logging_skew)
            if args.report:  # the HTML report is a synchronous request (?report=html): no job returns HTML
                Path(args.report).write_text(c.check_report(**_upload(args), max_logging_skew=args.max_logging_skew),
                                             encoding="utf-8")
    else:
        from ocp.identify import CheckOptions, check
        from ocp.identify.report import write_report
        from ocp.model.effects import load_plant

        log = _load_log(args)
        plant = load_plant(args.params)
        res = check(plant, log, _options(CheckOptions, max_logging_skew=args.max_logging_skew))
        if args.report:
            write_report(res, log, args.report, plant=plant)
        d = _annotate(res.to_dict(), log)
    if args.json:
        print_json(d)
        return 0
    if d.get("route") == "point-by-point":
        print_points(d)
        print_equations(d)
        return 0
    print_alignment(d)
    lag = d["free_run"].get("current_sensor_lag") or 0.0
    print("free run (model simulated under the measured voltage) RMS error"
          + (f"; current read through the sensor's lag fitted, {lag:.1f} samples:" if lag else ":"))
    for ch, v in d["free_run"]["rms"].items():
        print(f"  {ch:8s} {_g(v, '.4g')}   (sensor noise ~{_g(d['noise'][ch], '.3g')})")
    print("one-step equation residual RMS:")
    for eq, v in d["one_step"]["rms"].items():
        print(f"  {eq:10s} {_g(v, '.4g')}")
    print_equations(d)
    return 0


def cmd_diagnose(args: argparse.Namespace) -> int:
    if args.max_effects < 1:
        raise ParameterError("--max-effects", "must be >= 1")
    if args.server:
        _diagnose_options(args)  # checked here, named by the CLI option
        with client(args) as c:
            d = _server_job(c, "diagnose", args, **_diagnose_fields(args))
    else:
        from ocp.identify import diagnose
        from ocp.model.effects import load_plant

        log = _load_log(args)
        opt = _diagnose_options(args)
        with _Progress("diagnose") as bar:
            d = _annotate(diagnose(load_plant(args.params), log, opt, progress=bar.update).to_dict(), log)
    if args.json:
        print_json(d)
        return 0
    print_diagnosis(d)
    return 0


def _server_job(c: Any, op: str, args: argparse.Namespace, **fields: Any) -> dict[str, Any]:
    """``op`` on ``--server`` as a model-check job (stored, no request timeout), its progress drawn on stderr."""
    with _Progress(op) as bar:
        job = c.submit_model_check(op, **_upload(args), **fields)
        result: dict[str, Any] = c.wait_model_check(job["id"], on_progress=bar.update)
        return result


def _options(kind: type[_O], **values: Any) -> _O:
    """``kind(**values)``, a bad value named by its CLI option."""
    from pydantic import ValidationError

    try:
        return kind(**values)
    except ValidationError as exc:
        err = exc.errors()[0]
        raise ParameterError(f"--{str(err['loc'][0]).replace('_', '-')}", str(err["msg"])) from None


def _diagnose_options(args: argparse.Namespace) -> DiagnoseOptions:
    from ocp.identify import DiagnoseOptions

    return _options(DiagnoseOptions, max_effects=args.max_effects, include_params=not args.no_corrections,
                    tolerance=args.tolerance, max_logging_skew=args.max_logging_skew)


def _diagnose_fields(args: argparse.Namespace) -> dict[str, Any]:
    """Every diagnose option as the API's form fields (the server runs what the local command runs)."""
    return {"max_effects": args.max_effects, "corrections": not args.no_corrections, "tolerance": args.tolerance,
            "max_logging_skew": args.max_logging_skew}


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


def cmd_fit(args: argparse.Namespace) -> int:
    names = [n.strip() for n in args.effects.split(",") if n.strip()]
    if not names:
        raise ParameterError("--effects", "give at least one effect name")
    if args.server:
        with client(args) as c:
            d = _server_job(c, "fit", args, effects=",".join(names), refine=not args.no_refine,
                            max_logging_skew=args.max_logging_skew)
        if args.out:  # the same file FitResult.write makes
            Path(args.out).write_text(json.dumps(d["calibrated_params"], indent=2, allow_nan=False) + "\n",
                                      encoding="utf-8")
    else:
        from ocp.identify import FitOptions, fit
        from ocp.model.effects import load_plant

        log = _load_log(args)
        res = fit(load_plant(args.params), log, names,
                  _options(FitOptions, refine=not args.no_refine, max_logging_skew=args.max_logging_skew))
        if args.out:
            res.write(args.out)
        d = _annotate(res.to_dict(), log)
    if args.json:
        print_json(d)
        return 0
    print_alignment(d)
    print(f"fitted ({d['stage']} stage):")
    for n, p in d["parameters"].items():
        print(f"  {n:28s} {_g(p['value'], '.5g')}  +- {_g(p['stderr'], '.2g')}")
    lag = d.get("current_sensor_lag") or {}
    read = (f" (current read through the sensor's lag fitted, {lag['before']:.1f} -> {lag['after']:.1f} samples)"
            if any(lag.values()) else "")
    print(f"free-run RMS error   before -> after{read}:" if d.get("route") != "point-by-point" else
          "equation residual RMS   before -> after:")
    for ch in d["rms_before"]:
        print(f"  {ch:8s} {_g(d['rms_before'][ch], '.4g')} -> {_g(d['rms_after'][ch], '.4g')}")
    print_equations(d)
    if d.get("adopted") is False:  # (the file written, if any, is the starting plant)
        print(f"NOT ADOPTED -- {d['note']}")
    return 0
