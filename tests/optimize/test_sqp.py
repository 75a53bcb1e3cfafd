"""Issue 14: the flat program's first solver, SQP with qpOASES (:mod:`ocp.optimize.sqp`), and IPOPT behind it.

Oracles: IPOPT on the same NLP from the same start (an interior-point method: an independent solver of the same
optimum); a real SQP solver held to one iteration (it cannot converge) to show that IPOPT then answers; a fresh
process whose standard output must stay empty while a program is built and solved (qpOASES prints a banner).
"""

import dataclasses
import json
import subprocess
import sys
from pathlib import Path

import casadi as ca
import numpy as np

from ocp.optimize import flat, flat_solve, sqp
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for

ROOT = Path(__file__).resolve().parents[2]


def _reversal() -> tuple[flat.FlatProgram, flat_solve.FlatData, tuple[np.ndarray, np.ndarray]]:
    problem = problem_for(mission_from_mapping(json.loads((ROOT / "examples" / "reversal.json").read_text())))
    prog, _ = flat.program_for(flat_solve.structure_of(problem))
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    return prog, data, prog.g_bounds(1.0 - flat.MARGIN, 1.0 - flat.MARGIN)


def test_sqp_reaches_ipopts_optimum_in_fewer_iterations():
    """SQP answers the README's bounded reversal (no IPOPT run) at IPOPT's optimum: objective within 1e-4
    relative, limits kept at the check points, fewer iterations."""
    prog, data, bounds = _reversal()
    run = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds)
    sol = prog.solver(x0=data.x0, p=data.p, lbx=data.lbx, ubx=data.ubx, lbg=bounds[0], ubg=bounds[1])
    assert prog.solver.stats()["success"] and run.success and run.method == "sqpmethod"
    f_ipopt = float(sol["f"]) / data.p[flat.param_slices(prog.structure)["obj_scale"]][0]
    assert abs(run.objective / f_ipopt - 1.0) < 1e-4
    assert run.constraint_violation < 1e-7
    assert run.iterations < prog.solver.stats()["iter_count"]


def test_ipopt_answers_where_sqp_fails_and_the_iterations_add_up():
    """An SQP solver held to one iteration stops unconverged: IPOPT then solves from the same start to the same
    optimum, and the run reports IPOPT, its status and both solvers' iterations."""
    prog, data, bounds = _reversal()
    reference = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, bounds)
    one = ca.nlpsol("one", "sqpmethod", prog.nlp, {**sqp.OPTIONS, "max_iter": 1})
    held = dataclasses.replace(prog, sqp_solver=one, memory=type(prog.memory)(maxlen=1))
    run = flat.solve(held, data.p, data.lbx, data.ubx, data.x0, bounds)
    assert not one.stats()["success"]
    assert run.method == "ipopt" and run.success and run.status == "Solve_Succeeded"
    ipopt_iterations = prog.solver.stats()["iter_count"]
    assert run.iterations == 1 + ipopt_iterations
    assert abs(run.objective / reference.objective - 1.0) < 1e-4


def test_building_and_solving_keeps_standard_output_empty():
    """qpOASES's banner is kept off the process's standard output (the CLI writes its JSON answer there)."""
    code = ("import json; from ocp.optimize.mission import mission_from_mapping; "
            "from ocp.optimize.solve import optimize_mesh; "
            "r = optimize_mesh(mission_from_mapping(json.load(open('examples/reversal.json')))); "
            "import sys; print(r.solver.method, file=sys.stderr)")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=120,
                         env={"PYTHONPATH": str(ROOT), "PATH": "/usr/bin:/bin"}, check=True)
    assert out.stdout == "" and out.stderr.strip().endswith("sqpmethod")


def test_quiet_keeps_what_qpoases_prints_off_standard_output(capsys):
    """qpOASES's messages reach Python's ``sys.stdout`` through CasADi: a QP solver made outside :func:`sqp.quiet`
    prints its banner there (the oracle that the check can fail), one made and run inside prints nothing."""
    x = ca.SX.sym("x")
    qp = {"x": x, "f": x**2, "g": x}
    ca.qpsol("loud", "qpoases", qp, {"printLevel": "none"})
    assert "qpOASES" in capsys.readouterr().out
    with sqp.quiet():
        quiet = ca.qpsol("quiet", "qpoases", qp, {"printLevel": "none", "error_on_fail": False})
        quiet(lbx=0.0, ubx=1.0, lbg=2.0, ubg=3.0)  # infeasible
    assert capsys.readouterr().out == "" and not quiet.stats()["success"]
