"""Whether the reported ripple count can be trusted: on the proving-ground logs where a ripple is drawn or named,
the count found against the rig's, and whether the answer leaves the rig's count open (``rivals``).

    python bench/ripple_counts.py --n 200 --first 14000 --procs 2 --cache DIR [--no-angle]

Per log with ``cogging`` named: the rig's count, the best count, ``max_tracked_periods`` (an angle integrated from
the speed) and the rivals; then a table by angle source: right and decided, right but open, wrong with the rig's
count among the rivals (honest), wrong with it missing (misleading), false ripples. Session 36 (the 800 logs
0..199, 6000..6199, 14000..14199, 23000..23199, with and without their angle column): misleading 13 -> 1.
"""

from __future__ import annotations

import argparse
import functools
import sys
from collections import Counter
from multiprocessing import Pool
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import case_log, load_case


def one(seed: int, cache: str | None, angle: bool) -> dict[str, Any] | None:
    """The ripple's count, rivals and angle source on case ``seed`` where ``cogging`` is drawn or named, else None."""
    from ocp.identify import diagnose
    from ocp.model.params import MotorParams
    from ocp.model.plant import DCMotorPlant

    case = load_case(seed, cache)
    drawn = case.truth.effects.get("cogging", {}).get("periods")
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case, angle))
    ap = res.angle_periodic
    if "cogging" not in res.verdict or ap is None:
        return None if drawn is None else {"seed": seed, "drawn": int(drawn), "named": False}
    return {"seed": seed, "drawn": None if drawn is None else int(drawn), "named": True, "periods": ap["periods"],
            "rivals": ap["rivals"], "angle": ap["angle"], "tracked": ap.get("max_tracked_periods")}


def kind(r: dict[str, Any]) -> str:
    if r["drawn"] is None:
        return "false ripple"
    if r["periods"] == r["drawn"]:
        return "right, decided" if not r["rivals"] else "right, open"
    return "wrong, rig's count a rival" if r["drawn"] in r["rivals"] else "wrong, rig's count MISSING"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--n", type=int, default=200)
    ap.add_argument("--first", type=int, default=0)
    ap.add_argument("--procs", type=int, default=1)
    ap.add_argument("--cache", default=None, help="the generated logs' folder (bench/modelcheck.py --cache)")
    ap.add_argument("--no-angle", action="store_true", help="drop the angle column (the angle integrated)")
    args = ap.parse_args(argv)
    seeds = range(args.first, args.first + args.n)
    work = functools.partial(one, cache=args.cache, angle=not args.no_angle)
    with Pool(args.procs) as pool:
        rows = [r for r in pool.imap(work, seeds) if r is not None]
    named = [r for r in rows if r["named"]]
    print(f"{'seed':>6} {'angle':>10} {'rig':>4} {'found':>5} {'tracked':>7}  rivals")
    for r in named:
        print(f"{r['seed']:6d} {r['angle']:>10} {r['drawn'] or '-':>4} {r['periods']:5d} {r['tracked']!s:>7}  "
              f"{len(r['rivals'])}")
    table = Counter((r["angle"], kind(r)) for r in named)
    print(f"\nripples drawn: {sum(r['drawn'] is not None for r in rows)}, named: "
          f"{sum(r['drawn'] is not None for r in named)}; false ripples: {sum(r['drawn'] is None for r in named)}")
    for (source, k), c in sorted(table.items()):
        print(f"  {source:10s} {k:30s} {c:4d}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
