"""Issue 14: the flat program's first solver, an SQP with DAQP hot-started (:mod:`ocp.optimize.sqp`), and IPOPT
behind it.

Oracles: IPOPT on the same NLP from the same start (an interior-point method: an independent solver of the same
optimum); an SQP held to one iteration (it cannot converge) to show that IPOPT then answers; a deadline already
passed; a fresh process whose standard output must stay empty while a program is built and solved.
"""

import dataclasses
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bench.user_missions import user_missions
from ocp.optimize import flat, flat_solve, sqp
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for

ROOT = Path(__file__).resolve().parents[2]


def _program(spec: dict) -> tuple[flat.FlatProgram, flat_solve.FlatData, tuple[np.ndarray, np.ndarray]]:
    problem = problem_for(mission_from_mapping(spec))
    prog, _ = flat.program_for(flat_solve.structure_of(problem))
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    return prog, data, prog.g_bounds(1.0 - flat.MARGIN, 1.0 - flat.MARGIN)


def _reversal() -> tuple[flat.FlatProgram, flat_solve.FlatData, tuple[np.ndarray, np.ndarray]]:
    return _program(json.loads((ROOT / "examples" / "reversal.json").read_text()))


def _ipopt(prog: flat.FlatProgram, data: flat_solve.FlatData, bounds: tuple[np.ndarray, np.ndarray]) -> float:
    """IPOPT's objective (unscaled, as :func:`flat.solve` reports it) from the same start."""
    sol = prog.solver(x0=data.x0, p=data.p, lbx=data.lbx, ubx=data.ubx, lbg=bounds[0], ubg=bounds[1])
    assert prog.solver.stats()["success"]
    return float(sol["f"]) / data.p[flat.param_slices(prog.structure)["obj_scale"]][0]


def test_sqp_reaches_ipopts_optimum_in_fewer_iterations():
    """SQP answers the README's bounded reversal (no IPOPT run) at IPOPT's optimum: objective within 1e-4
    relative, limits kept at the check points, fewer iterations."""
    _sqp_at_ipopts_optimum(*_reversal())


def _sqp_at_ipopts_optimum(prog: flat.FlatProgram, data: flat_solve.FlatData,
                           bounds: tuple[np.ndarray, np.ndarray]) -> None:
    """The SQP answers alone, within 1e-4 of IPOPT's objective from the same start, its rows kept to 1e-7, in fewer
    iterations than IPOPT."""
    run = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds)
    f_ipopt = _ipopt(prog, data, bounds)
    assert run.success and run.method == "sqp"
    assert abs(run.objective / f_ipopt - 1.0) < 1e-4
    assert run.constraint_violation < 1e-7
    assert run.iterations < prog.solver.stats()["iter_count"]


def test_sqp_with_binding_current_rows_reaches_ipopts_optimum():
    """On the 1 Hz bounded user sine (four reversals, the current limit binding on every one: tens of limit rows
    active at the optimum, whose curvature the QP's Hessian keeps) the SQP reaches IPOPT's optimum within 1e-4
    relative, the rows kept to 1e-7, in fewer iterations than IPOPT (the hot start of its QPs is tested in
    ``test_daqp.py``)."""
    spec = next(m for m in user_missions() if m["name"] == "user-sine-1hz-b")
    prog, data, bounds = _program(spec)
    _sqp_at_ipopts_optimum(prog, data, bounds)
    lam = np.asarray(prog.memory[-1].lam_g)
    assert np.count_nonzero(lam[: 2 * prog.structure.n_phases * prog.n_check]) >= 10  # limit rows active


def test_ipopt_answers_where_sqp_fails_and_the_iterations_add_up():
    """An SQP solver held to one iteration stops unconverged: IPOPT then solves from the same start to the same
    optimum, and the run reports IPOPT, its status and both solvers' iterations."""
    prog, data, bounds = _reversal()
    reference = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds)
    one = sqp.build("one", prog.nlp, prog.deadline, prog.solver, max_iter=1)
    held = dataclasses.replace(prog, sqp_solver=one, memory=type(prog.memory)(maxlen=1))
    run = flat.solve(held, data.p, data.lbx, data.ubx, data.x0, bounds)
    assert not one.stats()["success"] and one.stats()["return_status"] == "Maximum_Iterations_Exceeded"
    assert run.method == "ipopt" and run.success and run.status == "Solve_Succeeded"
    ipopt_iterations = prog.solver.stats()["iter_count"]
    assert run.iterations == 1 + ipopt_iterations
    assert abs(run.objective / reference.objective - 1.0) < 1e-4


def test_a_passed_deadline_stops_the_sqp_before_its_first_step():
    """The program's deadline (``until`` of its iteration callback) stops the SQP between iterations: with a
    deadline already passed it returns the start unsolved, in IPOPT's words, after no iteration."""
    prog, data, bounds = _reversal()
    assert prog.sqp_solver is not None  # the flat program's SQP (program_for builds it)
    prog.deadline.until = time.perf_counter() - 1.0
    try:
        sol = prog.sqp_solver(x0=data.x0, p=data.p, lbx=data.lbx, ubx=data.ubx, lbg=bounds[0], ubg=bounds[1])
    finally:
        prog.deadline.until = float("inf")
    stats = prog.sqp_solver.stats()
    assert not stats["success"] and stats["return_status"] == "User_Requested_Stop" and stats["iter_count"] == 0
    np.testing.assert_array_equal(sol["x"], np.clip(data.x0, data.lbx, data.ubx))


def test_building_and_solving_keeps_standard_output_empty():
    """Nothing reaches the process's standard output while a program is built and solved (the CLI writes its
    JSON answer there)."""
    code = ("import json; from ocp.optimize.mission import mission_from_mapping; "
            "from ocp.optimize.solve import optimize_mesh; "
            "r = optimize_mesh(mission_from_mapping(json.load(open('examples/reversal.json')))); "
            "import sys; print(r.solver.method, file=sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}, check=True)
    assert out.stdout == "" and out.stderr.strip().endswith("sqp")
