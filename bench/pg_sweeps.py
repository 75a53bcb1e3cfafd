"""The model check on steady-state sweeps nobody here exported: the proving ground's rig held at each commanded voltage
(:mod:`tests.proving_ground.sweeps`, its own formulas), one row per settled point, read as a CSV sweep and diagnosed
point by point with the user's nominal constants. Prints the confusion matrix of ``bench/modelcheck.py``. ``--esc``:
the motor behind an ESC, logged as a thrust stand does (pulse width, unsigned RPM, the supply's voltage and current).

    python bench/pg_sweeps.py --n 200 --first 0 [--esc] [--procs 2] [--json OUT] [--compare OLD NEW]
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import compare, table


def one(args: tuple[int, bool]) -> dict[str, Any]:
    """Generate, write, read and diagnose sweep ``seed`` (through an ESC: ``esc``): its record (the fields
    :func:`bench.modelcheck.table` reads)."""
    from ocp.identify import diagnose
    from ocp.logs import read_log
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant
    from tests.logfiles import write_csv
    from tests.proving_ground.sweeps import make_sweep

    seed, esc = args
    t0 = time.perf_counter()
    sw = make_sweep(seed, esc)
    t1 = time.perf_counter()
    rec: dict[str, Any] = {"seed": seed, "kind": sw.kind, "expected": sorted(sw.expected), "required": [],
                           "verdict": [], "error": None, "points": len(next(iter(sw.columns.values()))),
                           "rate": 0.0,
                           "effects": sw.truth.effects, "t_generate": t1 - t0}
    try:
        with tempfile.TemporaryDirectory() as tmp:
            path = Path(tmp) / "sweep.csv"
            write_csv(sw.columns, path)
            res = diagnose(DCMotorPlant(MotorParams(**sw.nominal)), read_log(path, kind="steady-state"))
        rec["excitations"] = [f"{'ESC ' if esc else ''}sweep of {rec['points']} points"]
        rec["verdict"] = list(res.verdict)
        rec["ambiguous"] = [[a["adopted"], a["alternative"]] for a in res.ambiguous]
    except Exception as e:  # a crash is a finding: recorded, counted
        rec["error"] = f"{type(e).__name__}: {e}"
    rec["t_diagnose"] = time.perf_counter() - t1
    return rec


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--procs", type=int, default=2)
    ap.add_argument("--esc", action="store_true", help="the motor behind an ESC, logged as a thrust stand does")
    ap.add_argument("--json", type=Path)
    ap.add_argument("--compare", nargs=2, type=Path, metavar=("OLD", "NEW"))
    a = ap.parse_args(argv)
    if a.compare:
        old, new = (json.loads(p.read_text()) for p in a.compare)
        print(compare(old, new))
        return 0
    t0 = time.perf_counter()
    seeds = [(s, a.esc) for s in range(a.first, a.first + a.n)]
    if a.procs > 1:
        with mp.get_context("spawn").Pool(a.procs) as pool:
            rows = pool.map(one, seeds, chunksize=4)
    else:
        rows = [one(s) for s in seeds]
    print(table(rows))
    wrong = [r for r in rows if set(r["verdict"]) != set(r["expected"]) and not r["error"]]
    told = [r for r in wrong if any({a, b} & (set(r["expected"]) ^ set(r["verdict"])) for a, b in r["ambiguous"])]
    print(f"wrong verdicts whose ambiguity names a missed or a wrong label as a rival: {len(told)} of {len(wrong)}")
    for r in rows:
        if set(r["verdict"]) != set(r["expected"]):
            print(f"  {r['seed']:6d} {r['kind']:13s} expected {r['expected']} got {r['verdict']} "
                  f"({r['points']} points){' ' + r['error'] if r['error'] else ''}")
    print(f"wall time {time.perf_counter() - t0:.0f} s with {a.procs} processes")
    if a.json:
        a.json.write_text(json.dumps(rows, default=float))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
