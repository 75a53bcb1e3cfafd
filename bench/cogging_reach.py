"""Where an angle ripple can be found: the drawn ripples of recorded proving-ground runs, named or missed, against
how fast the ripple turns per logged sample on the rig's own angle.

    python bench/cogging_reach.py --records run_0.json run_6000.json ... --cache DIR

Reads ``bench/modelcheck.py --json`` records (with or without the angle column: the rig's angle is the same). For
each log with ``cogging`` drawn: the rig's count ``n`` and the largest count the log samples at least twice a period
on half its moving rows, ``pi / median |d theta|`` (``theta`` the rig's angle as logged by an encoder, or the
tachometer's speed summed over the samples: numpy here, not the identifier's :func:`ocp.identify.angle.angle_limits`,
whose note states the same reach to users). Prints recall by ``n`` over that reach. Session 37, the 800 logs
0..199, 6000..6199, 14000..14199, 23000..23199: within the reach 36 of 37 named (without the angle column 37 of 37),
beyond it 14 of 30 (14 of 30); twice beyond it and more, 9 of 24.
"""

from __future__ import annotations

import argparse
import itertools
import json
import math
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import load_case

#: bins of the drawn count over the log's reach
EDGES = (0.0, 1.0, 2.0, 4.0, math.inf)


def reach(case: Any) -> float:
    """The largest ripple count [periods/rev] sampled twice a period on half the moving rows of ``case``'s log."""
    cols = case.columns
    theta = cols["theta"] if "theta" in cols else np.cumsum(cols["omega"]) * float(np.median(np.diff(cols["t"])))
    step = np.abs(np.diff(theta))
    moving = step[step > 0]
    return math.pi / float(np.median(moving)) if moving.size else math.inf


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", nargs="+", required=True)
    ap.add_argument("--cache", default=None, help="as bench/modelcheck.py's")
    args = ap.parse_args(argv)
    rows: list[tuple[float, bool]] = []
    for rec in (r for f in args.records for r in json.loads(Path(f).read_text())):
        if "cogging" not in rec["expected"]:
            continue
        case = load_case(rec["seed"], args.cache)
        n, top = case.truth.effects["cogging"]["periods"], reach(case)
        named = "cogging" in rec["verdict"]
        rows.append((n / top, named))
        print(f"{rec['seed']:6d} {'named' if named else 'MISSED':6s} {int(n):3d} periods/rev, reach {top:7.1f} "
              f"({n / top:5.2f} x) at {case.logger.rate:6.0f} Hz, {case.logger.speed}", flush=True)
    print("\ndrawn count / reach    drawn  named  recall")
    for lo, hi in itertools.pairwise(EDGES):
        sel = [named for r, named in rows if lo < r <= hi]
        if sel:
            print(f"  {lo:4.0f} .. {hi:<8.0f}  {len(sel):6d} {sum(sel):6d}  {100 * sum(sel) / len(sel):5.1f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
