"""How visible each labelled item of recorded proving-ground runs is, split by whether the check named it: the
proving ground's own figure (the rig replayed under the logged commands with and without the item, the channels as
logged, RMS difference in the logger's noise levels per channel [speed, current, thrust]).

    python bench/pg_visibility.py --records run_0.json run_6000.json --cache DIR [--named-share 0.25]

Reads ``bench/modelcheck.py --json`` records; every missed item and a random share of the named ones are replayed
(two replays each; ``input_delay`` is left out: its replay is the command FIFO's, not a rig difference). Prints the
two distributions (median, quartiles, share under 3 noise levels) and how many items show only in an encoder's speed
(whose noise is its quantisation: far under what a check that estimates constants can match).
"""

from __future__ import annotations

import argparse
import json
import random
import sys
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.modelcheck import load_case
from tests.proving_ground import cases as pg
from tests.proving_ground.calibration import without
from tests.proving_ground.logger import logged, noise_levels


def visibility(case: Any, item: str) -> np.ndarray:
    """(3,) the item's RMS change of the logged [speed, current, thrust] in noise levels."""
    tr, lg, tau_m = case.truth, case.logger, case.meta["tau_m"]
    cmds = case.columns["voltage"]
    a, b = (logged(lg, pg._replay(x, cmds, lg, tau_m)) for x in (tr, without(case, item)))
    return np.sqrt(np.mean((a - b) ** 2, axis=1)) / noise_levels(lg)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", nargs="+", required=True)
    ap.add_argument("--cache", default=None, help="as bench/modelcheck.py's")
    ap.add_argument("--named-share", type=float, default=0.25, help="share of the named items replayed")
    args = ap.parse_args(argv)
    rng = random.Random(0)
    out: dict[bool, list[tuple[float, bool]]] = {True: [], False: []}
    for rec in (r for f in args.records for r in json.loads(Path(f).read_text())):
        for item in rec["expected"]:
            named = item in rec["verdict"]
            if item == "input_delay" or (named and rng.random() > args.named_share):
                continue
            case = load_case(rec["seed"], args.cache)
            v = visibility(case, item)
            only_speed = case.logger.speed == "encoder" and v[0] >= pg.VISIBLE and max(v[1:]) < pg.VISIBLE
            out[named].append((float(np.max(v)), only_speed))
            print(f"{rec['seed']:6d} {item:18s} {'named' if named else 'MISSED':6s} "
                  f"speed {v[0]:8.2f} current {v[1]:7.2f} thrust {v[2]:7.2f}", flush=True)
    for named, rows in out.items():
        if not rows:
            continue
        v = np.array([r[0] for r in rows])
        q = np.percentile(v, [25, 50, 75])
        print(f"{'named' if named else 'missed'}: {v.size} items, visibility quartiles {q[0]:.1f} / {q[1]:.1f} / "
              f"{q[2]:.1f} noise levels, {100 * np.mean(v < 3):.0f} % under 3, "
              f"{sum(r[1] for r in rows)} only in an encoder's speed")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
