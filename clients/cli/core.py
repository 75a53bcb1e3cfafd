"""Core commands: ``table``, ``analytic``, ``simulate``."""

from __future__ import annotations

import argparse
import json
import math
import sys

from clients.cli.help import add_command, write_text
from clients.cli.io import print_json, read_csv_columns, write_csv
from ocp.errors import MissionError


def register(sub: argparse._SubParsersAction) -> None:
    p = add_command(sub, "table", summary="Table I of the paper, regenerated from Lemma 1",
                    description="For each thrust crossing order p (thrust ~ |t|^p at a reversal): the order r of "
                                "the speed crossing and\nthe regularity of the ideal torque, current and voltage.",
                    examples=["thrustshape table", "thrustshape table --orders 1,3,5 --json"])
    p.add_argument("--orders", default="1,2,3,4,5,7", help="thrust orders p, comma-separated")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=cmd_table)

    p = add_command(sub, "analytic", summary="exact A sin^(2q+1) reference with its current and voltage",
                    description="Samples thrust, speed, current and voltage of the exact feedforward of\n"
                                "F(t) = A sin^(2q+1)(2 pi t / T + phi); CSV (t, thrust, omega, ...) on stdout.",
                    examples=["thrustshape analytic --params paper-rig --amplitude 0.5 --period 2 --q 2 > sin5.csv",
                              "thrustshape analytic --params examples/params.yaml --amplitude 0.3 --period 1 --q 1 "
                              "--json"],
                    lists=("presets",))
    p.add_argument("--params", required=True, help="parameter file (JSON/YAML) or preset name, e.g. paper-rig")
    p.add_argument("--amplitude", type=float, required=True, help="thrust amplitude A [N]")
    p.add_argument("--period", type=float, required=True, help="period T [s]")
    p.add_argument("--q", type=int, required=True, help="exponent index q: thrust ~ sin^(2q+1)")
    p.add_argument("--phase", type=float, default=0.0, help="phase phi [rad]")
    p.add_argument("--duration", type=float, default=None, help="length [s] (default: one period)")
    p.add_argument("--rate", type=float, default=1000.0, help="sampling rate [Hz]")
    p.add_argument("--format", choices=("csv", "json"), default="csv")
    p.add_argument("--json", action="store_true", help="same as --format json")
    p.add_argument("--out", default=None, help="output file (default or '-': stdout)")
    p.set_defaults(func=cmd_analytic)

    p = add_command(sub, "simulate", summary="drive the DC-motor plant with a voltage CSV (t,voltage)",
                    description="Integrates the plant under the sampled voltage; CSV (t, voltage, omega, current,\n"
                                "theta, thrust) on stdout. Any CSV with t and voltage columns works, e.g. the\n"
                                "output of 'analytic' or of 'optimize --out'.",
                    examples=["thrustshape analytic --params paper-rig --amplitude 0.5 --period 2 --q 2 > sin5.csv",
                              "thrustshape simulate sin5.csv --params paper-rig > response.csv",
                              "thrustshape optimize examples/reversal.json --out - | "
                              "thrustshape simulate - --params paper-rig | head"],
                    lists=("presets",))
    p.add_argument("voltage_csv", help="CSV with columns t [s], voltage [V] ('-': stdin)")
    p.add_argument("--params", required=True, help="parameter file or preset name")
    p.add_argument("--omega0", type=float, default=0.0, help="initial speed [rad/s]")
    p.add_argument("--current0", type=float, default=0.0, help="initial current [A]")
    p.add_argument("--hold", choices=("zoh", "linear"), default="zoh",
                   help="zoh: sampled command held per sample (default); linear: interpolated")
    p.add_argument("--out", default=None, help="output CSV (default or '-': stdout)")
    p.add_argument("--json", action="store_true", help="JSON output instead of CSV")
    p.set_defaults(func=cmd_simulate)


def cmd_table(args: argparse.Namespace) -> int:
    from ocp.theory.reversal import table_one

    try:
        orders = tuple(int(x) for x in args.orders.split(","))
    except ValueError:
        raise MissionError("--orders", "must be comma-separated integers") from None
    if any(p < 1 or p > 99 for p in orders):
        raise MissionError("--orders", "orders must be in 1..99")
    rows = [r.labels() for r in table_one(orders)]
    if args.json:
        print_json({"rows": rows, "columns": ["p", "r", "torque", "current", "voltage"]})
        return 0
    print(f"{'p':>3} {'r':>3}  {'torque':<22} {'current':<22} {'voltage':<22}")
    for r in rows:
        print(f"{r['p']:>3} {r['r']:>3}  {r['torque']!s:<22} {r['current']!s:<22} {r['voltage']!s:<22}")
    return 0


def cmd_analytic(args: argparse.Namespace) -> int:
    from ocp.model.params import load_params
    from ocp.reference.analytic import SinProfile, reference, time_grid

    params = load_params(args.params)
    prof = SinProfile(args.amplitude, args.period, args.q, args.phase)
    duration = args.period if args.duration is None else args.duration
    ref = reference(prof, params, time_grid(duration, args.rate))
    if args.json or args.format == "json":
        write_text(json.dumps(ref.to_dict(), allow_nan=False) + "\n", args.out)
        return 0
    write_text(ref.to_csv(), args.out)
    if any(ref.unbounded[c] for c in ("current", "voltage")):
        bad = [c for c in ("current", "voltage") if ref.unbounded[c]]
        print(f"thrustshape analytic: warning: {', '.join(bad)} unbounded at the crossings (q = {args.q}); "
              "samples there are +-inf", file=sys.stderr)
    return 0


def cmd_simulate(args: argparse.Namespace) -> int:
    import numpy as np

    from ocp.model.params import load_params
    from ocp.model.plant import DCMotorPlant
    from ocp.simulate.open_loop import simulate, simulate_zoh

    params = load_params(args.params)
    cols = read_csv_columns(args.voltage_csv, ("t", "voltage"))
    plant = DCMotorPlant(params)
    x0 = (args.omega0, args.current0)
    if not (math.isfinite(args.omega0) and math.isfinite(args.current0)):
        raise MissionError("--omega0", "initial state must be finite")
    sim = (simulate_zoh if args.hold == "zoh" else simulate)(plant, cols["t"], cols["voltage"], x0)
    out = {"t": sim.t, "voltage": sim.u, "omega": sim.state("omega"), "current": sim.state("current"),
           "theta": sim.theta, "thrust": sim.thrust}
    if args.json:
        print_json({k: np.asarray(v, float).tolist() for k, v in out.items()})
    else:
        write_csv(out, args.out)
    return 0
