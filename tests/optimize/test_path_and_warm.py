"""Issue 14: the current held inside the intervals by construction, and warm starts that IPOPT uses."""

import json
import math
from pathlib import Path

import casadi as ca
import numpy as np
from scipy.integrate import solve_ivp

from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.optimize import path_limits
from ocp.optimize.collocation import TAU
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.result import SolverProgram
from ocp.optimize.solve import optimize

RADAU = SolverProgram.RADAU  # the Radau program's own in-interval limits and warm starts (the flat one runs cold)

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())
SMALL_MOTOR = {"J": 4e-5, "B": 1e-6, "c_tau": 1e-6, "c_f": 2e-5, "k_t": 0.03, "k_e": 0.03, "R": 3.0, "L": 2e-3}


def test_the_in_interval_current_matches_an_independent_integration() -> None:
    """Speed linear over the interval, voltage held: the closed form at the check points equals Radau on
    eq. dc_electrical (L i' = V - R i - k_e w) to 1e-9 of the limit, for a rising and a falling transient."""
    p = MotorParams(**SMALL_MOTOR)
    plant = DCMotorPlant(p)
    hn, w_a, w_b = 0.017, 100.0, 93.0  # interval [s], speed at its start and end [rad/s]
    xs = np.array([120.0, 0.8])  # speed, current scales
    pts, uk, x_s, u_s = ca.SX.sym("pts", 2, TAU.size), ca.SX.sym("u"), ca.SX.sym("xs", 2), ca.SX.sym("us")
    # the interval's length a constant SX (the program passes a symbolic one)
    terms = path_limits.current_terms(plant, TAU, 0, 2, pts, uk, x_s, u_s, ca.SX(hn))
    fn = ca.Function("i", [pts, uk, x_s, u_s], [terms])
    for volts, i0 in ((-6.0, -0.2), (6.0, 0.75)):
        nodes = np.vstack([(w_a + (w_b - w_a) * TAU) / xs[0], np.full(TAU.size, i0 / xs[1])])
        got = np.asarray(fn(nodes, volts / 6.0, xs, 6.0)).ravel() * xs[1]
        t_check = np.array(path_limits.CHECK_TAU_E) * p.L / p.R
        sol = solve_ivp(lambda t, i, v=volts: [(v - p.R * i[0] - p.k_e * (w_a + (w_b - w_a) * t / hn)) / p.L],
                        (0.0, hn), [i0], method="Radau", rtol=1e-12, atol=1e-14, t_eval=t_check)
        np.testing.assert_allclose(got, sol.y[0], rtol=0, atol=1e-9)


def _ramp_mission() -> dict:
    t = np.linspace(0.0, 2.0, 401)  # 200 Hz
    f = 0.3 * np.clip(1.0 - 2.0 * (t - 0.5), -1.0, 1.0)
    return {"name": "small-motor-ramp", "params": SMALL_MOTOR, "limits": {"voltage": 6.0, "current": 0.8},
            "profile": {"t": t.tolist(), "thrust": f.tolist()}}


def test_a_binding_current_limit_holds_between_the_nodes_without_a_back_off_round() -> None:
    """A bounded ramp through zero on a small motor whose current limit binds (before: one back-off round on
    every such mission): the simulated answer keeps the limit on the integration grid at the first solve."""
    r = optimize(mission_from_mapping(_ramp_mission()), warm=False, program=RADAU)
    assert r.source == "optimized", r.reason
    assert r.solver["backoff_rounds"] == 0
    assert r.path_ok
    assert 0.99 * 0.8 < float(np.max(np.abs(r.fine["current"]))) <= 0.8 * 1.001  # binds, and holds


def test_a_repeated_request_starts_warm_and_lands_on_the_cold_answer() -> None:
    """Cold, then a 2 % different thrust (close: warm), then the first mission again (warm): the warm answer's
    objective is equal or better (the warm solver's tolerance is tighter), within 1e-3 relative. A mirrored
    mission (same structure, other speed signs) is not close: it starts cold."""
    base = mission_from_mapping(EXAMPLE)
    scaled = json.loads(json.dumps(EXAMPLE))
    mirrored = json.loads(json.dumps(EXAMPLE))
    for seg in scaled["segments"]:
        for key in ("thrust", "to"):
            if key in seg:
                seg[key] *= 1.02
    for seg in mirrored["segments"]:
        for key in ("thrust", "to"):
            if key in seg:
                seg[key] *= -1.0
    cold = optimize(base, warm=False, program=RADAU)
    near = optimize(mission_from_mapping(scaled), warm=None, program=RADAU)  # warm=None: what the service's workers ask
    again = optimize(base, warm=None, program=RADAU)
    assert not cold.solver["warm_start"] and near.solver["warm_start"] and again.solver["warm_start"]
    assert again.source == cold.source == "optimized"
    f_cold = cold.solver["objective"]
    assert f_cold * (1.0 - 1e-3) <= again.solver["objective"] <= f_cold * (1.0 + 1e-6)
    far = optimize(mission_from_mapping(mirrored), warm=None, program=RADAU)
    assert not far.solver["warm_start"]
    assert far.source == "optimized" and math.isclose(far.solver["objective"], cold.solver["objective"], rel_tol=1e-3)
