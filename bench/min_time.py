"""Min-time mesh refinement against the independent shooting solve (run on demand, not a test).

``python bench/min_time.py [--time-limit S]`` solves the +0.4 N -> -0.4 N reversal of ``examples/reversal.json``
at 1 A / 12 V in min-time mode, ``bounded`` and ``continuous-voltage``, with mesh refinement
(:mod:`ocp.optimize.min_time`), and prints every mesh's duration, the reported value with its error bound, the
independent solve of ``tests/optimize/test_min_time.py`` (scipy shooting on the optimal switching structure) and the
fastest ``sin^5`` reversal within the same limits.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

sys.path.insert(0, str(ROOT := Path(__file__).resolve().parents[1]))

from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.solve import optimize
from tests.optimize.test_min_time import oracle_min_time


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--time-limit", type=float, default=120.0, help="mission time_limit_s (refinement budget)")
    args = parser.parse_args()
    example = json.loads((ROOT / "examples" / "reversal.json").read_text())
    print(f"{'regularity':<20}{'meshes (intervals: ms)':<58}{'reported [ms]':>20}{'independent':>13}{'rel. err':>10}"
          f"{'sin^(2q+1)':>12}{'wall [s]':>10}")
    for regularity in ("bounded", "continuous-voltage"):
        m = mission_from_mapping({**example, "objective": "min-time", "regularity": regularity,
                                  "time_limit_s": args.time_limit})
        t0 = time.perf_counter()
        v = optimize(m).verification
        wall = time.perf_counter() - t0
        truth = oracle_min_time(regularity == "continuous-voltage")
        meshes = ", ".join(f"{row['intervals']}: {1e3 * row['min_time_s']:.2f}" for row in v["min_time_mesh"])
        bound = v["min_time_error_bound_s"]
        reported = "none" if v["min_time_s"] is None else (
            f"{1e3 * v['min_time_s']:.2f}" + ("" if bound is None else f" +- {1e3 * bound:.2f}"))
        err = "-" if v["min_time_s"] is None else f"{(v['min_time_s'] - truth) / truth:+.2%}"
        analytic = v["analytic_min_time_s"]
        print(f"{regularity:<20}{meshes:<58}{reported:>20}{1e3 * truth:>13.2f}{err:>10}"
              f"{'-' if analytic is None else f'{1e3 * analytic:.2f}':>12}{wall:>10.1f}")
        if v["min_time_note"]:
            print(f"{'':<20}({v['min_time_note']})")


if __name__ == "__main__":
    main()
