"""Wall time of ``thrustshape diagnose`` through its CLI, this tree against another, side by side.

Usage::

    git worktree add /tmp/old <commit>
    python bench/diagnose_time.py --old /tmp/old --dir /work/blind --seeds 109 196 34 151 95 5 --repeats 3

Each log is the blind rig's ``case-<seed>.csv`` with its ``case-<seed>.params.json`` (``bench/blind_check.py``
generates them into DIR). Per repeat and log the two trees run back to back, the order alternating, each a fresh
CLI process (start-up included) with ``PYTHONPATH`` at its tree, so the shared machine's load hits both alike. Prints
the rows of each log, the median wall time of each tree, their ratio, each tree's largest peak resident memory (the
process's own, from ``wait4``), and whether the verdicts agree; then the median per-log ratio. Not a test: always
exits 0.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent.parent


def run(tree: Path, csv: Path, params: Path) -> tuple[float, float, list[str]]:
    """Wall time [s], peak resident memory [GB] and verdict of one CLI run of ``diagnose`` with ``tree`` first on
    the path."""
    env = {**os.environ, "PYTHONPATH": str(tree)}
    cmd = [sys.executable, "-m", "clients.cli", "diagnose", str(csv), "--params", str(params), "--json"]
    t0 = time.perf_counter()
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        proc = subprocess.Popen(cmd, stdout=out, stderr=err, text=True, env=env, cwd="/")
        _, status, usage = os.wait4(proc.pid, 0)  # (this child's own rusage: ru_maxrss in KiB on Linux)
        proc.returncode = os.waitstatus_to_exitcode(status)
        wall = time.perf_counter() - t0
        out.seek(0)
        err.seek(0)
        try:
            return wall, usage.ru_maxrss * 1024 / 1e9, sorted(json.loads(out.read())["verdict"])
        except (json.JSONDecodeError, KeyError):
            return wall, usage.ru_maxrss * 1024 / 1e9, [f"error: {err.read().strip()[-200:]}"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", type=Path, required=True, help="the other source tree (e.g. a git worktree)")
    ap.add_argument("--dir", type=Path, required=True, help="folder of case-<seed>.csv / .params.json")
    ap.add_argument("--seeds", type=int, nargs="+", required=True)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    print(f"load average at start: {os.getloadavg()[0]:.2f}")
    print(f"{'seed':>6} {'rows':>7} {'old [s]':>8} {'new [s]':>8} {'new/old':>8} {'old GB':>7} {'new GB':>7}  verdicts")
    ratios = []
    for seed in args.seeds:
        csv, params = args.dir / f"case-{seed}.csv", args.dir / f"case-{seed}.params.json"
        with csv.open() as f:
            rows = sum(1 for _ in f) - 1
        times: dict[str, list[float]] = {"old": [], "new": []}
        peak = {"old": 0.0, "new": 0.0}
        verdicts: dict[str, list[str]] = {}
        for k in range(args.repeats):
            for name in (("old", "new") if k % 2 == 0 else ("new", "old")):
                wall, rss, verdicts[name] = run(args.old if name == "old" else HERE, csv, params)
                times[name].append(wall)
                peak[name] = max(peak[name], rss)
        old, new = statistics.median(times["old"]), statistics.median(times["new"])
        ratios.append(new / old)
        same = "same" if verdicts["old"] == verdicts["new"] else f"DIFFER old {verdicts['old']} new {verdicts['new']}"
        print(f"{seed:>6} {rows:>7} {old:>8.2f} {new:>8.2f} {new / old:>8.2f} {peak['old']:>7.2f} {peak['new']:>7.2f}  "
              f"{same}", flush=True)
    print(f"median per-log ratio new/old: {statistics.median(ratios):.2f};  "
          f"load average at end: {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
