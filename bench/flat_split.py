#!/usr/bin/env python
"""Where a cold flat-program answer's time goes, per mission (issue 14: which part to cut).

Usage::

    python bench/flat_split.py [--repeats N] [--suite all|classic|user]
    python bench/flat_split.py --sqp [--repeats N] [--suite ...]   # sqpmethod + qpOASES (first) vs IPOPT alone
    python bench/flat_split.py --sqp --batch 120 --repeats 1       # ... on bench/batch.py's mix (seed 7)

For every mission the flat program answers (``optimize_mesh``; the program built once, not timed) the cold
answer is computed ``repeats`` times; medians of: the whole call (wall), the NLP solver (wall, every round: SQP,
and IPOPT where SQP failed), the answer's packaging and verification (``solver["verify_time_s"]``), the rest
(problem data, guess, bookkeeping), and the CPU time of the solver runs alone (``time.process_time``: the part the
machine's load does not inflate), solver iterations, back-off rounds, and the limit rows of the program (current
and voltage at the check points). Not a test: it prints a table.

``--sqp``: the flat program's first solver, CasADi's ``sqpmethod`` with the sparse qpOASES (:mod:`ocp.optimize.sqp`;
:func:`ocp.optimize.flat.solve`, IPOPT behind it) against the program's IPOPT solver alone, on the same NLP and
start (the first round): per mission the median solve time, SQP iterations, objective against IPOPT's, whether SQP
answered alone, and whether the answer's simulated response keeps the limits (the verification of
:func:`ocp.optimize.flat_solve.solve_flat`, no back-off round).
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

from bench.batch import missions
from bench.optimizer import CLASSIC, SUITE
from bench.user_missions import USER, user_missions
from ocp.optimize import flat, flat_solve
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for
from ocp.optimize.result import SolverProgram, SolverStats
from ocp.optimize.solve import optimize_mesh


def _cpu_of_solve(problem: Any) -> float:
    """CPU seconds of one cold solve (:func:`flat.solve`) of the flat program on ``problem`` (the cached program,
    first round)."""
    prog, _ = flat.program_for(flat_solve.structure_of(problem))
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    bound = 1.0 - flat.MARGIN
    c0 = time.process_time()
    flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, prog.g_bounds(bound, bound))
    return time.process_time() - c0


def _sqp_row(problem: Any, repeats: int) -> tuple[float, float, int, float, bool, bool]:
    """(IPOPT ms, SQP ms, SQP iterations, SQP objective / IPOPT's - 1, SQP converged (no IPOPT behind it), the
    answer keeps the limits) on the flat program's first round from the static inverse: :func:`flat.solve` (SQP
    first) against the program's IPOPT solver alone from the same start."""
    st = flat_solve.structure_of(problem)
    prog, _ = flat.program_for(st)
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    bounds = prog.g_bounds(1.0 - flat.MARGIN, 1.0 - flat.MARGIN)
    runs = [flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds) for _ in range(repeats)]
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        sol = prog.solver(x0=data.x0, p=data.p, lbx=data.lbx, ubx=data.ubx, lbg=bounds[0], ubg=bounds[1])
        times.append(time.perf_counter() - t0)
    f_ipopt = float(sol["f"]) / float(data.p[flat.param_slices(st)["obj_scale"]][0])
    run = runs[-1]
    ok = run.method == "sqpmethod" and run.constraint_violation <= 1e-6
    kept = flat_solve._answer(problem, st, run.x, data, SolverStats(program=SolverProgram.FLAT)).path_ok
    return (1e3 * statistics.median(times), 1e3 * statistics.median(r.solve_time_s for r in runs), run.iterations,
            run.objective / f_ipopt - 1.0, ok, kept)


def sqp_trial(specs: list[dict[str, Any]], repeats: int) -> None:
    """Print the ``--sqp`` table and the medians of IPOPT and SQP over the missions."""
    print(f"load {os.getloadavg()[0]:.2f}; sqpmethod + qpOASES vs IPOPT, medians over {repeats} [ms]")
    print(f"{'mission':22s} {'ipopt':>7s} {'sqp':>7s} {'it':>3s} {'obj/ipopt-1':>11s} {'ok':>3s} {'limits':>6s}")
    rows = []
    for spec in specs:
        problem = problem_for(mission_from_mapping(spec))
        if flat_solve.applies(problem) is not None:
            continue
        row = _sqp_row(problem, repeats)
        rows.append(row)
        ok, kept = "yes" if row[4] else "no", "kept" if row[5] else "BROKE"
        print(f"{spec['name']:22s} {row[0]:7.1f} {row[1]:7.1f} {row[2]:3d} {row[3]:+11.1e} {ok:>3s} {kept:>6s}",
              flush=True)
    for k, name in ((0, "ipopt"), (1, "sqp")):
        print(f"{name}: median {statistics.median(r[k] for r in rows):.1f} ms, max {max(r[k] for r in rows):.1f} ms, "
              f"total {sum(r[k] for r in rows) / 1e3:.2f} s")
    print(f"sqp: objective above IPOPT's by more than 1e-3 on {sum(r[3] > 1e-3 for r in rows)}, IPOPT needed behind "
          f"it on {sum(not r[4] for r in rows)}, limits broken on {sum(not r[5] for r in rows)} of {len(rows)}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--suite", choices=("all", "classic", "user"), default="all")
    ap.add_argument("--sqp", action="store_true", help="instead: SQP (the flat program's first solver) vs IPOPT alone")
    ap.add_argument("--batch", type=int, default=0, help="with --sqp: the first N missions of bench/batch.py's mix")
    args = ap.parse_args(argv)
    names = {"all": CLASSIC + USER, "classic": CLASSIC, "user": USER}[args.suite]
    by_name = {s["name"]: s for s in SUITE + user_missions()}
    specs = [by_name[name] for name in names] if not args.batch else missions(args.batch, 7)
    if args.sqp:
        sqp_trial(specs, args.repeats)
        return 0
    print(f"load {os.getloadavg()[0]:.2f}; checks a span {flat.CHECKS}, at the ends {flat.END_CHECKS}; "
          f"IPOPT (behind SQP) {flat.IPOPT_OPTIONS}; medians over {args.repeats} [ms]")
    print(f"{'mission':22s} {'rows':>5s} {'it':>4s} {'bo':>3s} {'call':>7s} {'solver':>7s} {'verify':>7s} "
          f"{'rest':>6s} {'solve cpu':>9s} {'cpu/it':>7s}")
    for spec in specs:
        mission = mission_from_mapping(spec)
        problem = problem_for(mission)
        if flat_solve.applies(problem) is not None or optimize_mesh(mission).solver.program != SolverProgram.FLAT:
            continue
        runs = [optimize_mesh(mission, warm=False) for _ in range(args.repeats)]
        cpu = statistics.median(_cpu_of_solve(problem) for _ in range(args.repeats))
        call, solver, verify, rest = (statistics.median(f(r) for r in runs) for f in (
            lambda r: r.total_time_s, lambda r: r.solve_time_s, lambda r: float(r.solver.verify_time_s),
            lambda r: r.total_time_s - r.solve_time_s - float(r.solver.verify_time_s)))
        prog, _ = flat.program_for(flat_solve.structure_of(problem))
        it = runs[-1].solver.iterations
        print(f"{spec['name']:22s} {2 * prog.structure.n_phases * prog.n_check:5d} {it:4d} "
              f"{runs[-1].solver.backoff_rounds:3d} {call * 1e3:7.1f} {solver * 1e3:7.1f} {verify * 1e3:7.1f} "
              f"{rest * 1e3:6.1f} {cpu * 1e3:9.1f} {cpu * 1e3 / max(it, 1):7.2f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
