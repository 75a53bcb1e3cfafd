#!/usr/bin/env python
"""Where a cold flat-program answer's time goes, per mission (issue 14: which part to cut).

Usage::

    python bench/flat_split.py [--repeats N] [--suite all|classic|user]
    python bench/flat_split.py --sqp [--repeats N] [--suite ...]   # the SQP (first) vs IPOPT alone and sqpmethod
    python bench/flat_split.py --sqp --batch 120 --repeats 1       # ... on bench/batch.py's mix (seed 7)

For every mission the flat program answers (``optimize_mesh``; the program built once, not timed) the cold
answer is computed ``repeats`` times; medians of: the whole call (wall), the NLP solver (wall, every round: SQP,
and IPOPT where SQP failed), the answer's packaging and verification (``solver["verify_time_s"]``), the rest
(problem data, guess, bookkeeping), and the CPU time of the solver runs alone (``time.process_time``: the part the
machine's load does not inflate), solver iterations, back-off rounds, and the limit rows of the program (current
and voltage at the check points). Not a test: it prints a table.

``--sqp``: the flat program's first solver, the SQP with DAQP hot-started (:mod:`ocp.optimize.sqp`;
:func:`ocp.optimize.flat.solve`, IPOPT behind it) against the program's IPOPT solver alone and against CasADi's
``sqpmethod`` with the sparse qpOASES (the first solver until session 8), on the same NLP and start (the first
round): per mission the median solve time (wall) of each, the CPU time of the SQP and of sqpmethod, iterations of
both, the SQP's objective against IPOPT's, whether the SQP answered alone, and whether the answer's simulated
response keeps the limits (the verification of :func:`ocp.optimize.flat_solve.solve_flat`, no back-off round).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import os
import statistics
import sys
import time
from pathlib import Path
from typing import Any

import casadi as ca

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


def _sqpmethod(prog: flat.FlatProgram) -> Any:
    """CasADi's ``sqpmethod`` with the sparse qpOASES on the program's NLP (the flat program's first solver until
    session 8), quiet."""
    opts: dict[str, Any] = {"max_iter": 50, "tol_pr": 1e-7, "tol_du": 1e-7, "error_on_fail": False, "print_time": False,
                            "print_header": False, "print_iteration": False, "print_status": False, "qpsol": "qpoases",
                            "qpsol_options": {"printLevel": "none", "sparse": True, "error_on_fail": False}}
    with contextlib.redirect_stdout(io.StringIO()):
        return ca.nlpsol("sqpmethod", "sqpmethod", prog.nlp, opts)


def _timed(fn: Any, repeats: int) -> tuple[float, float, Any]:
    """Median wall and CPU time [ms] of ``repeats`` calls of ``fn`` (no arguments), and its last result."""
    walls, cpus = [], []
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        out = fn()
        walls.append(time.perf_counter() - w0)
        cpus.append(time.process_time() - c0)
    return 1e3 * statistics.median(walls), 1e3 * statistics.median(cpus), out


def _sqp_row(problem: Any, repeats: int) -> dict[str, Any]:
    """The first round of the flat program from the static inverse: :func:`flat.solve` (SQP first) against the
    program's IPOPT solver alone and CasADi's sqpmethod from the same start (times [ms], iterations, the SQP's
    objective / IPOPT's - 1, the SQP answered alone, the answer keeps the limits)."""
    st = flat_solve.structure_of(problem)
    prog, _ = flat.program_for(st)
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    bounds = prog.g_bounds(1.0 - flat.MARGIN, 1.0 - flat.MARGIN)
    args = {"x0": data.x0, "p": data.p, "lbx": data.lbx, "ubx": data.ubx, "lbg": bounds[0], "ubg": bounds[1]}
    sqp_wall, sqp_cpu, run = _timed(lambda: flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds), repeats)
    ipopt_wall, _, sol = _timed(lambda: prog.solver(**args), repeats)
    old = _sqpmethod(prog)
    with contextlib.redirect_stdout(io.StringIO()):
        old_wall, old_cpu, _ = _timed(lambda: old(**args), repeats)
    f_ipopt = float(sol["f"]) / float(data.p[flat.param_slices(st)["obj_scale"]][0])
    kept = flat_solve._answer(problem, st, run.x, data, SolverStats(program=SolverProgram.FLAT)).path_ok
    return {"ipopt": ipopt_wall, "sqpmethod": old_wall, "sqp": sqp_wall, "sqpmethod_cpu": old_cpu, "sqp_cpu": sqp_cpu,
            "it_old": int(old.stats()["iter_count"]), "it": run.iterations, "rel": run.objective / f_ipopt - 1.0,
            "ok": run.method == "sqp" and run.constraint_violation <= 1e-6, "kept": kept}


def sqp_trial(specs: list[dict[str, Any]], repeats: int) -> None:
    """Print the ``--sqp`` table and the medians of IPOPT, sqpmethod and the SQP over the missions."""
    print(f"load {os.getloadavg()[0]:.2f}; the SQP (DAQP) vs IPOPT and sqpmethod + qpOASES, medians over {repeats} "
          "[ms]")
    print(f"{'mission':22s} {'ipopt':>7s} {'sqpmeth':>7s} {'sqp':>7s} {'cpu old':>7s} {'cpu sqp':>7s} {'it':>5s} "
          f"{'obj/ipopt-1':>11s} {'ok':>3s} {'limits':>6s}")
    rows = []
    for spec in specs:
        problem = problem_for(mission_from_mapping(spec))
        if flat_solve.applies(problem) is not None:
            continue
        r = _sqp_row(problem, repeats)
        rows.append(r)
        ok, kept = "yes" if r["ok"] else "no", "kept" if r["kept"] else "BROKE"
        print(f"{spec['name']:22s} {r['ipopt']:7.1f} {r['sqpmethod']:7.1f} {r['sqp']:7.1f} {r['sqpmethod_cpu']:7.1f} "
              f"{r['sqp_cpu']:7.1f} {r['it_old']:2d}/{r['it']:<2d} {r['rel']:+11.1e} {ok:>3s} {kept:>6s}", flush=True)
    for name in ("ipopt", "sqpmethod", "sqp", "sqpmethod_cpu", "sqp_cpu"):
        print(f"{name}: median {statistics.median(r[name] for r in rows):.1f} ms, max {max(r[name] for r in rows):.1f} "
              f"ms, total {sum(r[name] for r in rows) / 1e3:.2f} s")
    print(f"sqp: objective above IPOPT's by more than 1e-3 on {sum(r['rel'] > 1e-3 for r in rows)}, IPOPT needed "
          f"behind it on {sum(not r['ok'] for r in rows)}, limits broken on {sum(not r['kept'] for r in rows)} of "
          f"{len(rows)}")


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
