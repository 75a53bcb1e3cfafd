"""Optimiser commands: ``optimize`` and ``compare``."""

from __future__ import annotations

import argparse
import math

from clients.cli.io import print_json, write_csv
from ocp.errors import MissionError
from ocp.mission import load_mission

CSV_COLUMNS = ("t", "thrust", "thrust_desired", "omega", "theta", "current", "voltage")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("optimize", help="optimise a mission's thrust reference under current/voltage limits")
    p.add_argument("mission", help="mission file (JSON or YAML)")
    p.add_argument("--json", action="store_true", help="print the full result as JSON")
    p.add_argument("--out", default=None, help="write the reference as CSV to this file")
    p.set_defaults(func=cmd_optimize)

    p = sub.add_parser("compare", help="optimised vs A sin^(2q+1) shapes of the same mission")
    p.add_argument("mission", help="mission file (JSON or YAML)")
    p.add_argument("--qs", default="0,1,2,3", help="q values of the analytic shapes, comma-separated")
    p.add_argument("--plot", default=None, help="write a PNG or SVG plot to this file")
    p.add_argument("--json", action="store_true", help="print the table as JSON")
    p.set_defaults(func=cmd_compare)


def cmd_optimize(args: argparse.Namespace) -> int:
    from ocp.optimize import optimize

    result = optimize(load_mission(args.mission))
    if args.out:
        write_csv({c: result.arrays[c] for c in CSV_COLUMNS}, args.out)
    if args.json:
        print_json(result.to_dict())
        return 0
    v = result.verification
    print(f"mission {result.name}: {result.source} ({result.status}){' - ' + result.reason if result.reason else ''}")
    print(f"  solve {result.solve_time_s * 1e3:.1f} ms, total {result.total_time_s * 1e3:.1f} ms, "
          f"stretch {', '.join(f'{s:.3f}' for s in result.stretch) or '-'}")
    print(f"  peaks |i| {v['max_abs_current']:.4g} A, |V| {v['max_abs_voltage']:.4g} V; reproduction rms "
          f"{v['thrust_rms_error']:.3g} N; tracking rms {v['tracking_rms_error']:.3g} N")
    for c in result.crossings:
        print(f"  reversal at {c['t']:.4f} s, local exponent {c['exponent']:.2f}")
    if not args.out:
        print("  (use --out FILE.csv for the arrays, --json for everything)")
    return 0


def _fmt(v: object) -> str:
    if isinstance(v, float):
        return "inf" if math.isinf(v) else f"{v:.4g}"
    if isinstance(v, list):
        return ",".join(_fmt(x) for x in v[:3]) + ("..." if len(v) > 3 else "")
    return str(v)


def cmd_compare(args: argparse.Namespace) -> int:
    from ocp.compare import compare, plot

    try:
        qs = tuple(int(q) for q in args.qs.split(","))
    except ValueError:
        raise MissionError("--qs", "must be comma-separated integers") from None
    result = compare(load_mission(args.mission), qs)
    if args.plot:
        plot(result, args.plot)
    if args.json:
        print_json(result.to_dict())
        return 0
    rows = result.table()
    cols = [k for k in rows[0] if k != "label"]
    print(f"{'shape':<22}" + "".join(f"{c[:14]:>16}" for c in cols))
    for r in rows:
        print(f"{r['label']:<22}" + "".join(f"{_fmt(r[c]):>16}" for c in cols))
    return 0
