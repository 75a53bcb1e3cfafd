"""Optimiser commands: ``optimize`` and ``compare``."""

from __future__ import annotations

import argparse
import math
import sys
from typing import TYPE_CHECKING, Any

from clients.cli.help import STDIO, add_command, read_text
from clients.cli.io import fmt_number as _g
from clients.cli.io import print_json, write_csv
from clients.cli.remote import add_server_args, client, params_for_server
from ocp.errors import MissionError

if TYPE_CHECKING:
    from ocp.optimize.mission import Mission

CSV_COLUMNS = ("t", "thrust", "thrust_desired", "omega", "theta", "current", "voltage")


def register(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "optimize", summary="optimise a mission's thrust reference under current/voltage limits",
                    description="A mission (JSON/YAML, see examples/reversal.json and ocp/optimize/mission.py) "
                                "gives the plant, the limits,\nthe reversal regularity, the objective and the desired "
                                "thrust. Prints a summary; --out writes\nthe reference as CSV (t, thrust, "
                                "thrust_desired, omega, theta, current, voltage).",
                    examples=["thrustshape optimize examples/reversal.json --out ref.csv --plot ref.svg",
                              "thrustshape optimize - --out - < examples/reversal.json | head",
                              "thrustshape optimize mission.yaml --server http://127.0.0.1:8000 --json"],
                    lists=("presets", "regularities"))
    p.add_argument("mission", help="mission file (JSON or YAML; '-': stdin)")
    p.add_argument("--json", action="store_true", help="print the full result as JSON")
    p.add_argument("--out", default=None, help="write the reference as CSV to this file ('-': stdout; the "
                                               "summary then goes to stderr; FILE.mat: MATLAB/Simulink)")
    p.add_argument("--plot", default=None, metavar="FILE", help="draw thrust, speed, current and voltage with the "
                                                                "limits (.svg, .png or .pdf)")
    add_server_args(p)
    p.set_defaults(func=cmd_optimize)

    p = add_command(sub, "compare", summary="optimised vs A sin^(2q+1) shapes of the same mission",
                    description="Peaks, energy, crossing exponents and the Section V closed-loop tracking of the "
                                "optimised\nreference beside the same mission with every reversal a "
                                "sin^(2q+1) half-wave.",
                    examples=["thrustshape compare examples/reversal.json --plot cmp.svg",
                              "thrustshape compare examples/reversal.json --qs 0,2 --json"],
                    lists=("presets",))
    p.add_argument("mission", help="mission file (JSON or YAML; '-': stdin)")
    p.add_argument("--qs", default="0,1,2,3", help="q values of the analytic shapes, comma-separated")
    p.add_argument("--plot", default=None, help="write a PNG or SVG plot to this file")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    add_server_args(p)
    p.set_defaults(func=cmd_compare)


def load_mission_arg(path: str) -> Mission:
    """The mission in ``path`` (JSON or YAML), or read from stdin for ``-``."""
    from ocp.optimize.mission import load_mission, mission_from_mapping

    if path != STDIO:
        return load_mission(path)
    import yaml  # JSON is YAML: one parser for both

    try:
        data = yaml.safe_load(read_text(path))
    except yaml.YAMLError as exc:
        raise MissionError("mission", f"stdin is not valid JSON/YAML: {exc}") from None
    return mission_from_mapping(data)


def _for_server(mission: Mission) -> dict[str, Any]:
    """The mission as JSON, a local parameter file replaced by its mapping (the server reads no files)."""
    body = mission.model_dump(mode="json")
    body["params"] = params_for_server(mission.params)
    return body


def cmd_optimize(args: argparse.Namespace) -> int:
    import numpy as np

    if args.out == STDIO and args.json:
        raise MissionError("--out", "'-' (stdout) cannot be combined with --json; give a file name")
    if args.plot:
        from clients.cli.plots import check_plot_path

        check_plot_path(args.plot)
    mission = load_mission_arg(args.mission)
    if args.server:
        with client(args) as c:
            d = c.optimize(_for_server(mission))
        if args.out:  # null in the JSON answer = a non-finite sample
            write_csv({k: np.array([math.nan if x is None else x for x in d[k]], float) for k in CSV_COLUMNS}, args.out)
    else:
        from ocp.optimize.solve import optimize

        result = optimize(mission)
        if args.out:
            write_csv({c: result.arrays[c] for c in CSV_COLUMNS}, args.out)
        d = result.to_dict()
    if args.plot:
        from clients.cli.plots import plot_reference

        plot_reference(d, {"current": mission.limits.current, "voltage": mission.limits.voltage}, args.plot)
    if args.json:
        print_json(d)
        return 0
    _summary(d, args.out, sys.stderr if args.out == STDIO else sys.stdout)
    return 0


def _summary(d: dict[str, Any], out: str | None, fh: Any) -> None:
    """The human-readable summary of an optimize answer, on ``fh``."""
    lines: list[str] = []
    say = lines.append
    v = d["verification"]
    say(f"mission {d['name']}: {d['source']} ({d['status']}){' - ' + d['reason'] if d['reason'] else ''}")
    s = d.get("solver") or {}
    parts = [f"{name} {_g(s[key], '.1f', 1e3)} ms" for name, key in
             (("build", "build_time_s"), ("verify", "verify_time_s")) if s.get(key)]
    say(f"  solve {_g(d['solve_time_s'], '.1f', 1e3)} ms ({s.get('iterations', '?')} IPOPT iterations), "
          + "".join(f"{p}, " for p in parts) + f"total {_g(d['total_time_s'], '.1f', 1e3)} ms, "
          f"stretch {', '.join(_g(x, '.3f') for x in d['stretch']) or '-'}")
    torque = f", |torque| {_g(v['max_abs_torque'], '.4g')} N m" if "max_abs_torque" in v else ""
    say(f"  peaks |i| {_g(v['max_abs_current'], '.4g')} A, |V| {_g(v['max_abs_voltage'], '.4g')} V{torque}; "
          f"reproduction rms {_g(v['thrust_rms_error'], '.3g')} N; tracking rms {_g(v['tracking_rms_error'], '.3g')} N")
    if "min_time_s" in v:
        analytic = v.get("analytic_min_time_s")
        bound = v.get("min_time_error_bound_s")
        found = "none" if v["min_time_s"] is None else f"{_g(v['min_time_s'], '.2f', 1e3)} ms"
        say(f"  minimum transition {found}; fastest analytic sin^(2q+1) within the "
              + ("same limits: none" if analytic is None else f"same limits {_g(analytic, '.1f', 1e3)} ms"))
        if bound is not None:
            say(f"  mesh refinement: error bound {_g(bound, '.2f', 1e3)} ms, meshes "
                  + ", ".join(f"{m['intervals']}: {_g(m['min_time_s'], '.2f', 1e3)} ms" for m in v["min_time_mesh"]))
        if v.get("min_time_note"):
            say(f"  ({v['min_time_note']})")
    for c in d["crossings"]:
        say(f"  reversal at {_g(c['t'], '.4f')} s, local exponent {_g(c['exponent'], '.2f')}")
    if not out:
        say("  (use --out FILE.csv for the arrays, --json for everything)")
    fh.write("".join(f"{line}\n" for line in lines))


def _fmt(v: object) -> str:
    if v is None:  # a JSON answer's non-finite value
        return "inf"
    if isinstance(v, float):
        return "inf" if math.isinf(v) else f"{v:.4g}"
    if isinstance(v, list):
        return ",".join(_fmt(x) for x in v[:3]) + ("..." if len(v) > 3 else "")
    return str(v)


def cmd_compare(args: argparse.Namespace) -> int:
    try:
        qs = tuple(int(q) for q in args.qs.split(","))
    except ValueError:
        raise MissionError("--qs", "must be comma-separated integers") from None
    mission = load_mission_arg(args.mission)
    if args.server:
        with client(args) as c:
            d = c.compare(_for_server(mission), qs=qs)
    else:
        from ocp.optimize.compare import compare

        d = compare(mission, qs).to_dict()
    rows = d["table"]
    if args.plot:
        from ocp.optimize.compare import plot

        plot(d, args.plot)
    if args.json:
        print_json(d)
        return 0
    cols = [k for k in rows[0] if k != "label"]
    print(f"{'shape':<22}" + "".join(f"{c[:14]:>16}" for c in cols))
    for r in rows:
        print(f"{r['label']:<22}" + "".join(f"{_fmt(r[c]):>16}" for c in cols))
    return 0
