"""Warm starts of the flat program (issue 14 item 2): cold vs warm, per mission, and where an answer's time goes.

Per mission (the user-like missions and the 2 s reversal), medians over the repeats, each repeat interleaved:

* cold: ``optimize_mesh(m, warm=False)``, from the static inverse;
* repeat: ``optimize_mesh(m, warm=None)`` right after ``m`` (a repeated service request);
* nearby: ``optimize_mesh(m, warm=None)`` right after ``m`` with every thrust x ``NEARBY`` (a batch item of the
  same structure; within ``ocp.optimize.warm.CLOSE``, so it starts warm).

Columns: IPOPT iterations, mission to solution (``total - verify``, as ``bench/optimizer.py``), its split
(setup: problem and data; IPOPT; verify: plan, held command, simulation, packaging), the worst relative objective
change of a warm answer against the cold one on one evaluator (``objective_of``; negative: better) and whether
every answer kept its limits on the simulated response. Run from ``bench/optimizer.py --warm`` or directly::

    python bench/flat_warm.py [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.user_missions import user_missions
from ocp.optimize.evaluate import objective_of
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for
from ocp.optimize.result import OptimizeResult
from ocp.optimize.solve import optimize_mesh

NEARBY = 1.05  # thrust scaling of the nearby predecessor
MODES = ("cold", "repeat", "nearby")
REVERSAL: dict[str, Any] = {
    "name": "reversal-2s", "limits": {"voltage": 12.0, "current": 1.0},
    "segments": [{"kind": "hold", "duration": 0.5, "thrust": 0.4},
                 {"kind": "reversal", "duration": 1.0, "to": -0.4, "shape": "cosine"},
                 {"kind": "hold", "duration": 0.5, "thrust": -0.4}]}


def scaled(spec: dict[str, Any], factor: float) -> dict[str, Any]:
    """``spec`` with every thrust level (profile samples, segment levels) times ``factor``."""
    out = {**spec, "name": f"{spec['name']}-x{factor:g}"}
    if "profile" in spec:
        out["profile"] = {**spec["profile"], "thrust": [factor * f for f in spec["profile"]["thrust"]]}
    if "segments" in spec:
        out["segments"] = [{k: factor * v if k in ("thrust", "to", "amplitude", "offset") else v
                            for k, v in seg.items()} for seg in spec["segments"]]
    return out


def _one(mode: str, m: Any, nearby: Any) -> OptimizeResult:
    if mode == "cold":
        return optimize_mesh(m, warm=False)
    optimize_mesh(m if mode == "repeat" else nearby, warm=False)
    return optimize_mesh(m, warm=None)


def bench_warm(spec: dict[str, Any], repeats: int) -> dict[str, Any]:
    """Medians per mode: iterations, times [s] (solution, setup, ipopt, verify); objective change; limits held."""
    m, nearby = mission_from_mapping(spec), mission_from_mapping(scaled(spec, NEARBY))
    problem = problem_for(m)
    for mode in MODES:  # builds (cold and warm solvers) outside the timing
        _one(mode, m, nearby)
    runs: dict[str, list[OptimizeResult]] = {mode: [] for mode in MODES}
    for _ in range(repeats):
        for mode in MODES:
            runs[mode].append(_one(mode, m, nearby))
    f_cold = objective_of(problem, runs["cold"][-1])
    out: dict[str, Any] = {"name": spec["name"], "program": str(runs["cold"][-1].solver.program)}
    for mode, rs in runs.items():
        s = [r.solver for r in rs]
        out[mode] = {"iterations": statistics.median(x.iterations for x in s),
                     "solution": statistics.median(r.total_time_s - x.verify_time_s
                                                   for r, x in zip(rs, s, strict=True)),
                     "setup": statistics.median(x.setup_time_s for x in s),
                     "ipopt": statistics.median(x.solve_time_s for x in s),
                     "verify": statistics.median(x.verify_time_s for x in s),
                     "warm": all(x.warm_start for x in s), "backoff": max(x.backoff_rounds for x in s),
                     "d_objective": max(objective_of(problem, r) / f_cold - 1.0 for r in rs),
                     "limits_held": all(r.path_ok for r in rs)}
    return out


def warm_report(repeats: int = 5, print_: Callable[[str], None] = print) -> list[dict[str, Any]]:
    """Run :func:`bench_warm` over the user-like missions and the 2 s reversal; print one table, return the rows."""
    rows = [bench_warm(spec, repeats) for spec in [*user_missions(), REVERSAL]]
    print_(f"\nflat program warm starts ({repeats} repeats; nearby = thrust x{NEARBY}); times in ms, "
           "solution = setup + ipopt (+ back-off rounds' verification); load "
           + " ".join(f"{x:.1f}" for x in os.getloadavg()))
    head = f"{'mission':22s} {'prog':5s}" + "".join(
        f" | {mode:>6s} it   sol setup ipopt verif" for mode in MODES) + " | d obj warm  limits"
    print_(head)
    print_("-" * len(head))
    for r in rows:
        cells = "".join(f" | {'w' if r[mode]['warm'] else 'c'}{r[mode]['iterations']:5.0f} "
                        + " ".join(f"{1e3 * r[mode][k]:5.1f}" for k in ("solution", "setup", "ipopt", "verify"))
                        for mode in MODES)
        d_obj = max(r[mode]["d_objective"] for mode in MODES[1:])
        held = all(r[mode]["limits_held"] for mode in MODES)
        print_(f"{r['name']:22s} {r['program']:5s}{cells} | {d_obj:+.1e}  {'held' if held else 'BROKEN'}")
    for mode in MODES:
        sol = [r[mode]["solution"] for r in rows if r["name"] != REVERSAL["name"]]
        print_(f"user suite, {mode:6s}: median {1e3 * statistics.median(sol):.1f} ms, max {1e3 * max(sol):.1f} ms, "
               f"median iterations {statistics.median(r[mode]['iterations'] for r in rows):.0f}")
    worst = max(r[mode]["d_objective"] for r in rows for mode in MODES[1:])
    print_(f"warm objective within 1e-3 of cold (or better): {'PASS' if worst <= 1e-3 else 'FAIL'} "
           f"(worst {worst:+.1e})")
    return rows


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    warm_report(ap.parse_args(argv).repeats)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
