#!/usr/bin/env python
"""Where a cold flat-program answer's time goes, per mission (issue 14: which part to cut).

Usage::

    python bench/flat_split.py [--repeats N] [--suite all|classic|user]

For every mission the flat program answers (``optimize_mesh``; the program built once, not timed) the cold
answer is computed ``repeats`` times; medians of: the whole call (wall), IPOPT (wall, every round), the answer's
packaging and verification (``solver["verify_time_s"]``), the rest (problem data, guess, bookkeeping), and the
CPU time of the IPOPT runs alone (``time.process_time``: the part the machine's load does not inflate), IPOPT
iterations, back-off rounds, and the limit rows of the program (current and voltage at the check points). Not
a test: it prints a table.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from bench.optimizer import CLASSIC, SUITE
from bench.user_missions import USER, user_missions
from ocp.optimize import flat, flat_solve
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for
from ocp.optimize.result import SolverProgram
from ocp.optimize.solve import optimize_mesh


def _cpu_of_ipopt(problem: Any) -> float:
    """CPU seconds of one cold IPOPT run of the flat program on ``problem`` (the cached program, first round)."""
    prog, _ = flat.program_for(flat_solve.structure_of(problem))
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    bound = 1.0 - flat.MARGIN
    c0 = time.process_time()
    flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, prog.g_bounds(bound, bound))
    return time.process_time() - c0


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--suite", choices=("all", "classic", "user"), default="all")
    args = ap.parse_args(argv)
    names = {"all": CLASSIC + USER, "classic": CLASSIC, "user": USER}[args.suite]
    by_name = {s["name"]: s for s in SUITE + user_missions()}
    specs = [by_name[name] for name in names]
    print(f"load {os.getloadavg()[0]:.2f}; checks a span {flat.CHECKS}, at the ends {flat.END_CHECKS}; "
          f"IPOPT {flat.IPOPT_OPTIONS}; medians over {args.repeats} [ms]")
    print(f"{'mission':22s} {'rows':>5s} {'it':>4s} {'bo':>3s} {'call':>7s} {'ipopt':>7s} {'verify':>7s} "
          f"{'rest':>6s} {'ipopt cpu':>9s} {'cpu/it':>7s}")
    for spec in specs:
        mission = mission_from_mapping(spec)
        problem = problem_for(mission)
        if flat_solve.applies(problem) is not None or optimize_mesh(mission).solver.program != SolverProgram.FLAT:
            continue
        runs = [optimize_mesh(mission, warm=False) for _ in range(args.repeats)]
        cpu = statistics.median(_cpu_of_ipopt(problem) for _ in range(args.repeats))
        call, ipopt, verify, rest = (statistics.median(f(r) for r in runs) for f in (
            lambda r: r.total_time_s, lambda r: r.solve_time_s, lambda r: float(r.solver.verify_time_s),
            lambda r: r.total_time_s - r.solve_time_s - float(r.solver.verify_time_s)))
        prog, _ = flat.program_for(flat_solve.structure_of(problem))
        it = runs[-1].solver.iterations
        print(f"{spec['name']:22s} {2 * prog.structure.n_phases * prog.n_check:5d} {it:4d} "
              f"{runs[-1].solver.backoff_rounds:3d} {call * 1e3:7.1f} {ipopt * 1e3:7.1f} {verify * 1e3:7.1f} "
              f"{rest * 1e3:6.1f} {cpu * 1e3:9.1f} {cpu * 1e3 / max(it, 1):7.2f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
