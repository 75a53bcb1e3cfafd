"""A current clipped at its sensor's range (:mod:`ocp.identify.clipping`): the proving ground's clean time-series
cases (:func:`bench.modelcheck.load_case`), each with its current clipped at a share of its peak, diagnosed with the
clipped rows left out (as shipped) and with them fitted like any other (the detection switched off).

    python bench/clipped_current.py --first 0 --n 200 --cache DIR [--level 0.45] [--procs 2]

Prints how many clean logs come back clean either way, the false items named ("refused": too few rows left to check,
said by an error), and the logs as drawn (unclipped) where a clipped current is wrongly detected. ~2 s a clean log.
"""

from __future__ import annotations

import argparse
import sys
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import case_log, load_case


def _one(seed: int, cache: str | None, level: float) -> tuple[int, str, bool, list[str], list[str]] | None:
    """(seed, kind, detected as drawn, verdict handled, verdict unhandled) of a clean case; None for other kinds."""
    from dataclasses import replace

    import numpy as np

    import ocp.identify.clipping as clipping
    import ocp.identify.holdout as holdout
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant

    case = load_case(seed, cache, False)
    log = case_log(case, True)
    drawn = bool(clipping.clipped(log.current).any())
    if case.kind != "clean":
        return (seed, case.kind, drawn, [], []) if drawn else None
    top = level * float(np.max(np.abs(log.current)))
    cut = replace(log, current=np.clip(log.current, -top, top))
    plant = DCMotorPlant(MotorParams(**case.nominal))
    handled = _verdict(plant, cut)
    holdout.clipped = lambda x: np.zeros(x.size, dtype=bool)  # (the split's and the equations' cut: holdout.usable)
    try:
        unhandled = _verdict(plant, cut)
    finally:
        holdout.clipped = clipping.clipped
    return seed, case.kind, drawn, handled, unhandled


def _verdict(plant: Any, log: Any) -> list[str]:
    """The diagnosis' verdict, or ``["refused"]`` where it raises a LogError (too few rows left to check)."""
    from ocp.errors import LogError
    from ocp.identify import diagnose

    try:
        return list(diagnose(plant, log).verdict)
    except LogError:
        return ["refused"]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--cache", default=None, help="the proving ground's cache (bench/modelcheck.py --cache)")
    ap.add_argument("--level", type=float, default=0.45, help="clip at this share of the current's peak")
    ap.add_argument("--procs", type=int, default=2)
    args = ap.parse_args(argv)
    seeds = range(args.first, args.first + args.n)
    with ProcessPoolExecutor(args.procs) as pool:
        rows = [r for r in pool.map(_one, seeds, [args.cache] * len(seeds), [args.level] * len(seeds)) if r]
    clean = [r for r in rows if r[1] == "clean"]
    false_drawn = [r[0] for r in rows if r[2]]
    print(f"seeds {args.first}..{args.first + args.n - 1}: {len(clean)} clean logs, current clipped at "
          f"{100 * args.level:.0f} % of its peak")
    for name, verdicts in (("clipped rows left out (shipped)", [r[3] for r in clean]),
                           ("clipped rows fitted (detection off)", [r[4] for r in clean])):
        named = Counter(i for v in verdicts for i in v)
        print(f"  {name:38s} clean {sum(not v for v in verdicts):3d}/{len(clean)}   false items: "
              + (", ".join(f"{i} {n}" for i, n in named.most_common()) or "none"))
    print(f"  still named with the rows left out: {[(r[0], r[3]) for r in clean if r[3]]}")
    print(f"logs as drawn (every kind, unclipped) called clipped: {len(false_drawn)} {false_drawn}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
