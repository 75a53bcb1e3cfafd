"""Issue 14 item 2: warm starts of the flat program (primal and dual) across requests and back-off rounds.

Oracles: the cold answer to the same mission (same program, from the static inverse), both scored by one evaluator
of what the user receives (:func:`ocp.optimize.evaluate.objective_of`); the verification's simulation of the held
command for the limits; scipy's own spline derivatives for the plan's evaluation.
"""

import numpy as np
import pytest
from scipy.interpolate import BSpline

from ocp.optimize import flat, flat_solve, warm
from ocp.optimize.evaluate import objective_of
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for
from ocp.optimize.solve import optimize_mesh

SMALL_MOTOR = {"J": 4e-5, "B": 1e-6, "c_tau": 1e-6, "c_f": 2e-5, "k_t": 0.03, "k_e": 0.03, "R": 3.0, "L": 2e-3}
LIMITS = {"voltage": 6.0, "current": 0.8}


def _ramp(level: float = 0.3, regularity: str = "bounded") -> dict:
    """The issue's small motor, a 200 Hz ramp through zero (held at either end), the 0.8 A limit binding."""
    t = np.linspace(0.0, 2.0, 401)
    f = level * np.clip(1.0 - 2.0 * (t - 0.5), -1.0, 1.0)
    return {"name": f"ramp-{level}", "params": SMALL_MOTOR, "limits": LIMITS, "regularity": regularity,
            "profile": {"t": t.tolist(), "thrust": f.tolist()}}


def _holds_limits(r) -> None:
    v = r.verification
    assert r.source == "optimized" and r.solver.program == "flat" and r.path_ok
    assert v.max_abs_current <= LIMITS["current"] * (1 + 1e-3)
    assert v.max_abs_voltage <= LIMITS["voltage"] * (1 + 1e-3)


@pytest.mark.parametrize("regularity", ["bounded", "continuous-voltage"])
def test_a_repeated_or_nearby_request_starts_warm_and_answers_as_well(regularity):
    """After a mission 5 % stronger (within ``warm.CLOSE``), and after the same mission again, ``warm=None`` starts
    from the program's memory: fewer IPOPT iterations than cold, the objective equal or better (rel 1e-3) on one
    evaluator, the limits held on the simulated answer."""
    m, nearby = mission_from_mapping(_ramp(0.3, regularity)), mission_from_mapping(_ramp(0.315, regularity))
    problem = problem_for(m)
    cold = optimize_mesh(m, warm=False)
    _holds_limits(cold)
    assert not cold.solver.warm_start
    for previous in (nearby, m):
        optimize_mesh(previous, warm=False)
        again = optimize_mesh(m, warm=None)
        _holds_limits(again)
        assert again.solver.warm_start
        assert again.solver.iterations < cold.solver.iterations
        assert objective_of(problem, again) <= objective_of(problem, cold) * (1.0 + 1e-3)


def test_a_distant_request_starts_cold_and_an_older_near_one_warm():
    """Half the thrust (beyond ``warm.CLOSE``) or another motor's constants: no start from the memory; a request
    near an older solve than the last (a batch of mixed items of one structure) starts from that one."""
    optimize_mesh(mission_from_mapping(_ramp(0.3)), warm=False)
    assert not optimize_mesh(mission_from_mapping(_ramp(0.15)), warm=None).solver.warm_start
    other = _ramp(0.3)
    other["params"] = {**SMALL_MOTOR, "R": 2.0 * SMALL_MOTOR["R"]}
    assert not optimize_mesh(mission_from_mapping(other), warm=None).solver.warm_start
    back = optimize_mesh(mission_from_mapping(_ramp(0.31)), warm=None)
    assert back.solver.warm_start and back.path_ok


def _memory(level: float, size: int = 4) -> warm.Memory:
    p = np.array([1.0, 2.0, level, level])  # sigma, dur, fd (2)
    return warm.Memory(x=np.full(size, level), lam_x=np.zeros(size), lam_g=np.zeros(1), p=p, lbx=np.zeros(size),
                       ubx=np.ones(size))


def test_pick_takes_the_nearest_plausible_memory():
    """``warm.pick``: the nearest remembered solve within CLOSE (``None`` beyond it, or with another exact part),
    the latest when asked (``warm=True``), none when told not to or when the size differs."""
    slices = {"sigma": slice(0, 1), "dur": slice(1, 2), "fd": slice(2, 4)}
    mems = [_memory(1.0), _memory(2.0), _memory(5.0)]
    lo, hi = np.zeros(4), np.ones(4)

    def pick(level: float, how: bool | None = None, sigma: float = 1.0, size: int = 4) -> warm.Memory | None:
        p = np.array([sigma, 2.0, level, level])
        return warm.pick(mems, how, p, np.zeros(size), np.ones(size), slices, ("sigma",), ("dur",))

    assert pick(1.9) is mems[1] and pick(1.05) is mems[0] and pick(4.5) is mems[2]
    assert pick(3.5) is None  # 3.5 vs 2 and 5: 43 % and 30 % of the peak
    assert pick(2.0, sigma=-1.0) is None and pick(2.0, how=False) is None and pick(2.0, size=3) is None
    assert pick(100.0, how=True) is mems[2]
    assert warm.start_from(mems[0], None, np.array([1.0, 2.0, 1.1, 1.1]), lo, hi, slices, ("sigma",), ("dur",))


def test_a_backoff_round_starts_from_the_previous_round():
    """A back-off round (current and voltage bounds at the check points tightened by 3 %) solved from the previous
    round's primal takes fewer iterations than from the static inverse, to the same objective (rel 1e-6)."""
    problem = problem_for(mission_from_mapping(_ramp(0.3)))
    prog, _ = flat.program_for(flat_solve.structure_of(problem))
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    loose, tight = prog.g_bounds(0.995, 0.995), prog.g_bounds(0.965, 0.965)
    cold = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, tight)
    first = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, loose)
    again = flat.solve(prog, data.p, data.lbx, data.ubx, first.x, tight)
    assert cold.success and first.success and again.success and not again.warm
    assert again.iterations < cold.iterations
    assert abs(again.objective - cold.objective) <= 1e-6 * cold.objective


def test_the_plans_derivatives_are_scipys():
    """The plan's speed and its time derivatives are scipy's spline derivatives of the solved coefficients over
    the phase lengths (the plan derives its splines once; the values must not change)."""
    problem = problem_for(mission_from_mapping(_ramp(0.3)))
    st = flat_solve.structure_of(problem)
    prog, _ = flat.program_for(st)
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    run = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, prog.g_bounds(0.995, 0.995))
    plan = flat_solve.plan_of(problem, st, run.x, data)
    edges = plan.phase_edges
    t = np.linspace(0.0, edges[-1], 2001)
    w, _ = plan.derivatives(t)
    P, nc = st.n_phases, st.n_coef
    coef = run.x[P:].reshape(P, nc) * data.scales.x[0]
    for j in range(P):
        sel = (t >= edges[j]) & (t < edges[j + 1])
        h = edges[j + 1] - edges[j]
        spline = BSpline(flat.knots(st.spans), coef[j], flat.DEGREE)
        for r in range(3):
            expect = (spline.derivative(r) if r else spline)((t[sel] - edges[j]) / h) / h**r
            np.testing.assert_array_equal(w[r][sel], expect)


def test_a_cold_solve_converges_whatever_the_objective_units():
    """A mission whose objective is ~2e-7 (the paper rig's 2 s reversal): the cold solve ends where a warm solve
    from it, at the warm solver's tolerance of 1e-10, finds nothing better (one evaluator, 1e-5 relative). IPOPT's
    tolerances are absolute; without the objective's scale (``flat.objective_scaled``) it stopped 1 % above."""
    m = mission_from_mapping({"name": "reversal-2s", "limits": {"voltage": 12.0, "current": 1.0}, "segments": [
        {"kind": "hold", "duration": 0.5, "thrust": 0.4},
        {"kind": "reversal", "duration": 1.0, "to": -0.4, "shape": "cosine"},
        {"kind": "hold", "duration": 0.5, "thrust": -0.4}]})
    problem = problem_for(m)
    cold = optimize_mesh(m, warm=False)
    polished = optimize_mesh(m, warm=True)
    assert cold.solver.program == "flat" and polished.solver.warm_start
    assert objective_of(problem, cold) < 1e-6  # the small-objective case this test is about
    assert objective_of(problem, cold) == pytest.approx(objective_of(problem, polished), rel=1e-5)
