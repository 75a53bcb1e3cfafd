"""Optimiser commands: ``optimize`` and ``compare``."""

from __future__ import annotations

import argparse
import math
from typing import Any

import numpy as np

from clients.cli.io import fmt_number as _g
from clients.cli.io import print_json, write_csv
from clients.cli.remote import add_server_args, client, params_for_server
from ocp.errors import MissionError
from ocp.mission import Mission, load_mission

CSV_COLUMNS = ("t", "thrust", "thrust_desired", "omega", "theta", "current", "voltage")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("optimize", help="optimise a mission's thrust reference under current/voltage limits")
    p.add_argument("mission", help="mission file (JSON or YAML)")
    p.add_argument("--json", action="store_true", help="print the full result as JSON")
    p.add_argument("--out", default=None, help="write the reference as CSV to this file (FILE.mat: MATLAB/Simulink)")
    add_server_args(p)
    p.set_defaults(func=cmd_optimize)

    p = sub.add_parser("compare", help="optimised vs A sin^(2q+1) shapes of the same mission")
    p.add_argument("mission", help="mission file (JSON or YAML)")
    p.add_argument("--qs", default="0,1,2,3", help="q values of the analytic shapes, comma-separated")
    p.add_argument("--plot", default=None, help="write a PNG or SVG plot to this file")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    add_server_args(p)
    p.set_defaults(func=cmd_compare)


def _for_server(mission: Mission) -> dict[str, Any]:
    """The mission as JSON, a local parameter file replaced by its mapping (the server reads no files)."""
    body = mission.model_dump(mode="json")
    body["params"] = params_for_server(mission.params)
    return body


def cmd_optimize(args: argparse.Namespace) -> int:
    mission = load_mission(args.mission)
    if args.server:
        with client(args) as c:
            d = c.optimize(_for_server(mission))
        if args.out:  # null in the JSON answer = a non-finite sample
            write_csv({k: np.array([math.nan if x is None else x for x in d[k]], float) for k in CSV_COLUMNS}, args.out)
    else:
        from ocp.optimize import optimize

        result = optimize(mission)
        if args.out:
            write_csv({c: result.arrays[c] for c in CSV_COLUMNS}, args.out)
        d = result.to_dict()
    if args.json:
        print_json(d)
        return 0
    v = d["verification"]
    print(f"mission {d['name']}: {d['source']} ({d['status']}){' - ' + d['reason'] if d['reason'] else ''}")
    s = d.get("solver") or {}
    parts = [f"{name} {_g(s[key], '.1f', 1e3)} ms" for name, key in
             (("build", "build_time_s"), ("verify", "verify_time_s")) if s.get(key)]
    print(f"  solve {_g(d['solve_time_s'], '.1f', 1e3)} ms ({s.get('iterations', '?')} IPOPT iterations), "
          + "".join(f"{p}, " for p in parts) + f"total {_g(d['total_time_s'], '.1f', 1e3)} ms, "
          f"stretch {', '.join(_g(x, '.3f') for x in d['stretch']) or '-'}")
    torque = f", |torque| {_g(v['max_abs_torque'], '.4g')} N m" if "max_abs_torque" in v else ""
    print(f"  peaks |i| {_g(v['max_abs_current'], '.4g')} A, |V| {_g(v['max_abs_voltage'], '.4g')} V{torque}; "
          f"reproduction rms {_g(v['thrust_rms_error'], '.3g')} N; tracking rms {_g(v['tracking_rms_error'], '.3g')} N")
    if "min_time_s" in v:
        analytic = v.get("analytic_min_time_s")
        print(f"  minimum transition {_g(v['min_time_s'], '.1f', 1e3)} ms; fastest analytic sin^(2q+1) within the "
              + ("same limits: none" if analytic is None else f"same limits {_g(analytic, '.1f', 1e3)} ms"))
    for c in d["crossings"]:
        print(f"  reversal at {_g(c['t'], '.4f')} s, local exponent {_g(c['exponent'], '.2f')}")
    if not args.out:
        print("  (use --out FILE.csv for the arrays, --json for everything)")
    return 0


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
    mission = load_mission(args.mission)
    if args.server:
        with client(args) as c:
            d = c.compare(_for_server(mission), qs=qs)
    else:
        from ocp.compare import compare

        d = compare(mission, qs).to_dict()
    rows = d["table"]
    if args.plot:
        from ocp.compare import plot

        plot(d, args.plot)
    if args.json:
        print_json(d)
        return 0
    cols = [k for k in rows[0] if k != "label"]
    print(f"{'shape':<22}" + "".join(f"{c[:14]:>16}" for c in cols))
    for r in rows:
        print(f"{r['label']:<22}" + "".join(f"{_fmt(r[c]):>16}" for c in cols))
    return 0
