"""Issue 14 item 3: the flat program (omega as a B-spline per phase) as the fast path, Radau as the reference.

Oracles: the Radau program's answer to the same mission, both scored by one evaluator
(:func:`ocp.optimize.evaluate.objective_of`); an independent simulation (scipy's Radau integrator on the DC motor
equations written out here) of the returned command; finite differences of the planned speed.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import BSpline

from ocp.optimize import flat, flat_solve
from ocp.optimize.evaluate import objective_of
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import Problem, problem_for
from ocp.optimize.result import SolverProgram
from ocp.optimize.solve import optimize, optimize_mesh

SMALL_MOTOR = {"J": 4e-5, "B": 1e-6, "c_tau": 1e-6, "c_f": 2e-5, "k_t": 0.03, "k_e": 0.03, "R": 3.0, "L": 2e-3}


def _reversal(regularity: str, current: float = 1.0, **extra) -> dict:
    """The 2 s paper-rig reversal (hold, cosine reversal, hold)."""
    return {"name": f"rev-{regularity}", "limits": {"voltage": 12.0, "current": current}, "regularity": regularity,
            "segments": [{"kind": "hold", "duration": 0.5, "thrust": 0.4},
                         {"kind": "reversal", "duration": 1.0, "to": -0.4, "shape": "cosine"},
                         {"kind": "hold", "duration": 0.5, "thrust": -0.4}], **extra}


def _user_ramp(regularity: str) -> dict:
    """The issue's small motor, a 200 Hz ramp through zero, the 0.8 A limit binding."""
    t = np.linspace(0.0, 2.0, 401)
    f = 0.3 * np.clip(1.0 - 2.0 * (t - 0.5), -1.0, 1.0)
    return {"name": f"ramp-{regularity}", "params": SMALL_MOTOR, "limits": {"voltage": 6.0, "current": 0.8},
            "regularity": regularity, "profile": {"t": t.tolist(), "thrust": f.tolist()}}


@pytest.mark.parametrize("spec", [_reversal("bounded"), _reversal("continuous-voltage")], ids=["bounded", "cv"])
def test_flat_objective_is_equal_or_better_than_radau(spec):
    """The flat answer scores at least as well as the Radau program's (rel 1e-3) on one evaluator of what the user
    receives (simulated thrust, held command), and both keep the limits."""
    m = mission_from_mapping(spec)
    problem = problem_for(m)
    flat_answer = optimize_mesh(m)
    radau = optimize_mesh(m, program=SolverProgram.RADAU)
    assert flat_answer.solver.program == "flat" and radau.solver.program == "radau"
    assert flat_answer.source == radau.source == "optimized"
    assert flat_answer.path_ok and radau.path_ok
    assert objective_of(problem, flat_answer) <= objective_of(problem, radau) * (1.0 + 1e-3)


def _rhs(p: dict, volts):
    def f(t, x):
        w, i = x
        # J w' = k_t i - B w - c_tau w|w|;  L i' = V - R i - k_e w  (written out here, not the project's plant)
        return [(p["k_t"] * i - p["B"] * w - p["c_tau"] * w * abs(w)) / p["J"],
                (volts(t) - p["R"] * i - p["k_e"] * w) / p["L"]]
    return f


def test_flat_answer_keeps_the_limits_in_an_independent_simulation():
    """The binding 0.8 A limit and the 6 V limit hold along scipy's integration of the held command (dense
    output, every 0.1 ms), and the returned thrust is what that simulation produces."""
    spec = _user_ramp("bounded")
    r = optimize(mission_from_mapping(spec))
    assert r.source == "optimized" and r.solver.program == "flat"
    ct, cv = r.arrays["command_t"], r.arrays["command"]

    def volts(t: float) -> float:
        return float(cv[min(max(int(np.searchsorted(ct, t, side="right")) - 1, 0), cv.size - 1)])

    w0 = math.sqrt(0.3 / SMALL_MOTOR["c_f"])
    i0 = (SMALL_MOTOR["B"] * w0 + SMALL_MOTOR["c_tau"] * w0**2) / SMALL_MOTOR["k_t"]
    t = np.arange(0.0, float(ct[-1]), 1e-4)
    sol = solve_ivp(_rhs(SMALL_MOTOR, volts), (0.0, float(ct[-1])), [w0, i0], method="LSODA", t_eval=t,
                    rtol=1e-9, atol=1e-11, max_step=2.5e-4)
    assert sol.success
    assert np.max(np.abs(sol.y[1])) <= 0.8 * (1 + 2e-3)
    assert np.max(np.abs(cv)) <= 6.0 * (1 + 1e-9)
    assert np.max(np.abs(sol.y[1])) >= 0.8 * 0.98  # the limit binds: a check that can fail both ways
    thrust = SMALL_MOTOR["c_f"] * sol.y[0] * np.abs(sol.y[0])
    np.testing.assert_allclose(np.interp(r.arrays["t"], t, thrust), r.arrays["thrust"], atol=2e-3 * 0.3)


def solved(spec: dict) -> tuple[Problem, flat.FlatStructure, flat_solve.FlatData, flat.col.Solved]:
    """The mission ``spec``'s problem, flat structure and data, and one successful cold solve (bounds 0.995)."""
    problem = problem_for(mission_from_mapping(spec))
    st = flat_solve.structure_of(problem)
    prog, _ = flat.program_for(st)
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    run = flat.solve(prog, data.p, data.lbx, data.ubx, data.x0, prog.g_bounds(0.995, 0.995))
    assert run.success
    return problem, st, data, run


def _solved_plan(spec: dict) -> tuple[flat_solve.FlatPlan, Problem]:
    problem, st, data, run = solved(spec)
    return flat_solve.plan_of(problem, st, run.x, data), problem


def test_spline_current_and_voltage_match_finite_differences_of_the_speed():
    """i = (J w' + B w + c_tau w|w|)/k_t and V = R i + L i' + k_e w with w', i' by central differences of the
    planned speed (step 1e-6 s) agree with the program's closed forms to 1e-6 of the limits."""
    plan, _ = _solved_plan(_user_ramp("continuous-voltage"))
    p, d = SMALL_MOTOR, 1e-6
    t = np.linspace(0.01, plan.phase_edges[-1] - 0.01, 700)
    t = t[np.min(np.abs(t[:, None] - plan.phase_edges[None, :]), axis=1) > 5 * d]  # not across a reversal

    def w(tt):
        return plan.states(tt)[0][0]

    def cur(tt):
        ww = w(tt)
        return (p["J"] * (w(tt + d) - w(tt - d)) / (2 * d) + p["B"] * ww + p["c_tau"] * ww * np.abs(ww)) / p["k_t"]

    (w_plan, i_plan), v_plan = plan.states(t)
    np.testing.assert_allclose(cur(t), i_plan, atol=1e-6 * 0.8)
    v_fd = p["R"] * cur(t) + p["L"] * (cur(t + d) - cur(t - d)) / (2 * d) + p["k_e"] * w_plan
    np.testing.assert_allclose(v_fd, v_plan, atol=1e-5 * 6.0)


def test_order_6_crossing_has_zero_current_and_voltage_and_cubic_speed():
    """Continuous voltage (order 6): at the reversal i = V = 0 and omega ~ s^3 (omega(2s)/omega(s) -> 8)."""
    plan, _ = _solved_plan(_reversal("continuous-voltage"))
    ts = float(plan.phase_edges[1])
    (w, i), v = plan.states(np.array([ts, ts + 1e-4, ts + 2e-4, ts - 1e-4, ts - 2e-4]))
    assert abs(i[0]) <= 1e-9 and abs(v[0]) <= 1e-9
    assert w[2] / w[1] == pytest.approx(8.0, rel=0.02) and w[4] / w[3] == pytest.approx(8.0, rel=0.02)
    assert np.sign(w[1]) == -np.sign(w[3])  # a reversal


def test_order_2_crossing_keeps_the_current_continuous_and_nonzero():
    """Bounded (order 2): omega ~ s at the reversal: the current is continuous and nonzero there, the voltage
    bounded."""
    plan, problem = _solved_plan(_reversal("bounded"))
    p = problem.mission.motor()
    ts = float(plan.phase_edges[1])
    (w, i), v = plan.states(np.array([ts - 1e-9, ts + 1e-9, ts + 1e-5]))
    assert abs(i[0] - i[1]) <= 1e-6
    assert abs(i[1]) >= 0.05
    assert np.all(np.abs(v) <= 12.0)
    # omega ~ s with the slope k_t i / J of eq. dc_mechanical at omega = 0
    assert w[2] / 1e-5 == pytest.approx(p.k_t * i[1] / p.J, rel=1e-2)


def test_unsupported_plant_goes_to_the_radau_program():
    """The torque channel has no flat program here: the Radau program answers, and says so."""
    m = mission_from_mapping({**_reversal("bounded"), "plant": "torque", "limits": {"torque": 0.02}})
    assert flat_solve.applies(problem_for(m)) is not None
    r = optimize(m)
    assert r.source == "optimized" and r.solver.program == "radau"
    assert r.to_dict()["solver"]["program"] == "radau"


def test_check_points_are_densest_in_the_end_spans():
    """CHECKS a span in the middle, END_CHECKS (outermost first) in the spans at either end, the phase end included;
    strictly increasing in [0, 1]."""
    spans = 8
    pts = flat.points(spans)["check"]
    edges = flat.knots(spans)[flat.DEGREE:-flat.DEGREE]
    per_span = np.histogram(pts[:-1], bins=edges)[0]
    ends = list(flat.END_CHECKS)
    assert per_span.tolist() == ends + [flat.CHECKS] * (spans - 2 * len(ends)) + ends[::-1]
    assert pts[-1] == 1.0 and pts[0] == 0.0 and np.all(np.diff(pts) > 0)


def test_initial_guess_is_inside_the_current_limit_and_tracks_the_holds():
    """The cold start's speed spline needs at most the current limit (eq. dc_mechanical written out here, omega' by
    central differences of the guess, every 0.5 ms), where the plain static inverse needs several times it at the
    reversal; on the holds (0.5 A of drag current) it is the static inverse sqrt(F / c_f) (within 1 %)."""
    spec = _user_ramp("bounded")
    problem = problem_for(mission_from_mapping(spec))
    st = flat_solve.structure_of(problem)
    prog, _ = flat.program_for(st)
    data = flat_solve.flat_data(problem, prog)
    assert data is not None
    p, lim, P = SMALL_MOTOR, spec["limits"]["current"], st.n_phases
    edges = problem.phases.bounds
    for j in range(P):
        spline = BSpline(flat.knots(st.spans), data.x0[P:].reshape(P, -1)[j] * data.scales.x[0], flat.DEGREE)
        tau, d = np.arange(0.0, 1.0, 5e-4 / (edges[j + 1] - edges[j]))[1:], 1e-6
        w = spline(tau)
        dw = (spline(tau + d) - spline(tau - d)) / (2 * d) / (edges[j + 1] - edges[j])
        cur = (p["J"] * dw + p["B"] * w + p["c_tau"] * w * np.abs(w)) / p["k_t"]
        assert np.max(np.abs(cur)) <= lim
        hold = np.abs(edges[j] + tau * (edges[j + 1] - edges[j]) - 1.0) > 0.6  # t < 0.4 s or t > 1.6 s
        np.testing.assert_allclose(np.abs(w[hold]), math.sqrt(0.3 / p["c_f"]), rtol=1e-2)


def test_user_sine_solves_without_a_backoff_round():
    """The 1 Hz continuous-voltage sine of the user suite (5 phases, the current limit binding near every
    reversal): the flat program's first answer keeps the limits on the integration grid (no back-off round)."""
    t = np.linspace(0.0, 2.0, 401)
    spec = {"name": "sine-cv", "params": SMALL_MOTOR, "limits": {"voltage": 6.0, "current": 1.0},
            "regularity": "continuous-voltage",
            "profile": {"t": t.tolist(), "thrust": (0.25 * np.cos(2 * np.pi * t)).tolist()}}
    r = optimize(mission_from_mapping(spec))
    assert r.source == "optimized" and r.solver.program == "flat"
    assert r.path_ok and r.solver.backoff_rounds == 0
