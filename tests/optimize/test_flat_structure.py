"""Issue 14 (batches): the Radau intervals are a parameter of the flat program, not part of its cache key.

Oracles: a program built the old way (the intervals a constant of the objective, substituted into the same NLP
before the solver is built) and the closed form of how the smoothness term scales with the intervals
(the Radau program's sum over its ``P N`` intervals, sampled once a span: ``(spans / N) / (P N)``).
"""

import casadi as ca
import numpy as np

from ocp.optimize import flat, flat_solve, sqp
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for


def _two_reversals(intervals: int) -> dict:
    """Hold, ramp reversal, hold, ramp reversal back, hold (``bench/batch.py``'s kind): three phases."""
    seg = [{"kind": "hold", "duration": 0.4, "thrust": 0.3},
           {"kind": "reversal", "duration": 0.5, "to": -0.3, "shape": "ramp"},
           {"kind": "hold", "duration": 0.4, "thrust": -0.3},
           {"kind": "reversal", "duration": 0.5, "to": 0.3, "shape": "ramp"},
           {"kind": "hold", "duration": 0.4, "thrust": 0.3}]
    return {"name": f"two-{intervals}", "limits": {"voltage": 12.0, "current": 1.0}, "regularity": "bounded",
            "collocation": {"intervals": intervals}, "segments": seg}


def _data(intervals: int) -> tuple[flat.FlatStructure, flat_solve.FlatData, flat.FlatProgram]:
    problem = problem_for(mission_from_mapping(_two_reversals(intervals)))
    st = flat_solve.structure_of(problem)
    prog, _ = flat.program_for(st)
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    return st, data, prog


def test_missions_of_other_intervals_share_one_program_with_unchanged_answers():
    """40 and 60 intervals over three phases (13 and 20 a phase, 8 spans both, doubled for the ramps' corners)
    are one flat structure; the shared program, used first for 60, answers the 40-interval mission exactly as a
    program with 13 intervals built in as a constant (1e-12, the same iterations)."""
    st40, d40, prog = _data(40)
    st60, d60, prog60 = _data(60)
    assert st40 == st60 and prog is prog60
    assert d40.p[flat.param_slices(st40)["intervals"]].tolist() == [13.0]
    bounds = prog.g_bounds(0.995, 0.995)
    flat.solve(prog, d60.p, d60.lbx, d60.ubx, d60.x0, bounds)
    shared = flat.solve(prog, d40.p, d40.lbx, d40.ubx, d40.x0, bounds)
    # the old program: the same NLP with the intervals a constant (no parameter left to set)
    sl = flat.param_slices(st40)["intervals"]
    par = prog.nlp["p"]
    fixed = {k: ca.substitute(prog.nlp[k], par[sl.start], ca.SX(13.0)) for k in ("f", "g")}
    assert not ca.depends_on(fixed["f"], par[sl.start])
    assert shared.method == "sqp"  # the flat program's first solver answered: the old program's is the same
    old = sqp.build("old", {"x": prog.nlp["x"], "p": par, **fixed}, prog.deadline)
    sol = old(x0=d40.x0, p=d40.p, lbx=d40.lbx, ubx=d40.ubx, lbg=bounds[0], ubg=bounds[1])
    assert shared.success and old.stats()["success"]
    np.testing.assert_allclose(shared.x, np.asarray(sol["x"]).ravel(), rtol=0, atol=1e-12)
    unscaled = float(sol["f"]) / float(d40.p[flat.param_slices(st40)["obj_scale"]][0])  # flat.solve reports this
    assert abs(shared.objective - unscaled) <= 1e-12 * abs(shared.objective)
    assert shared.iterations == old.stats()["iter_count"]


def test_intervals_parameter_scales_the_smoothness_term_as_the_radau_sum():
    """At one decision vector, the objective's change with the intervals N is the smoothness term's
    ``(spans / N) / (P N)`` = const / N^2 (closed form), and nothing else moves: f(N) - f(M) over
    f(N) - f(K) equals (1/N^2 - 1/M^2) / (1/N^2 - 1/K^2)."""
    st, data, prog = _data(40)
    f = ca.Function("f", [prog.nlp["x"], prog.nlp["p"]], [prog.nlp["f"]])
    sl = flat.param_slices(st)["intervals"]
    rng = np.random.default_rng(3)
    x = data.x0 + 0.5 * rng.standard_normal(data.x0.size)  # a control that is not smooth: a term that moves
    x[: st.n_phases] = 1.0  # no stretch term
    w = flat.param_slices(st)["weights"]

    def at(n: float) -> float:
        p = data.p.copy()
        p[sl] = n
        p[w.start] = 0.0  # no tracking term: the smoothness term is not lost in rounding against it
        return float(f(x, p))

    n, m, k = 13.0, 20.0, 40.0
    assert at(n) - at(m) > 1e-3 * abs(at(n))
    expected = (1 / n**2 - 1 / m**2) / (1 / n**2 - 1 / k**2)
    assert abs((at(n) - at(m)) / (at(n) - at(k)) - expected) <= 1e-9


def test_basis_tables_are_scipys_design_matrix_and_a_partition_of_unity():
    """The basis at the check points is scipy's design matrix (its own evaluation path, 1e-14); the functions sum
    to 1 everywhere and their tau-derivatives to 0 (a B-spline basis is a partition of unity)."""
    from scipy.interpolate import BSpline

    for spans in (8, 14, 20):
        tau = flat.points(spans)["check"]
        dm = BSpline.design_matrix(tau, flat.knots(spans), flat.DEGREE).toarray()
        np.testing.assert_allclose(flat.basis(spans, tau, 0), dm, rtol=0, atol=1e-14)
        np.testing.assert_allclose(flat.basis(spans, tau, 0).sum(axis=1), 1.0, rtol=0, atol=1e-13)
        for r in range(1, 5):
            table = flat.basis(spans, tau, r)
            assert table.shape == (tau.size, spans + flat.DEGREE)
            np.testing.assert_allclose(table.sum(axis=1), 0.0, atol=1e-9 * np.max(np.abs(table)))
