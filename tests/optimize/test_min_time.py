"""Min-time answers against an independent solve: scipy shooting on the switching structure of the optimum.

The oracle shares no code with ``ocp`` (own equations, scipy DOP853 at rtol 1e-11, brentq). The time-optimal
+0.4 N -> -0.4 N reversal of the paper rig at |i| <= 1 A, |V| <= 12 V is bang -- boundary -- bang: V = -12 V
until the current reaches -1 A, the current held at -1 A (V = -R + k_e w, inside the limits), then
V = +12 V until the current reaches its end value, switched so that the speed arrives at the same moment.
With ``continuous-voltage`` the reversal is split at w = 0, where i = V = 0 too (g = 6): each half is the same
structure (a continuous V with unbounded slew reaches the jumps in the limit, so the infimum is the same
piecewise-constant V). One switching speed per arc is found by brentq.
"""

from __future__ import annotations

import itertools
import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from ocp.optimize import data as opt_data
from ocp.optimize import min_time
from ocp.optimize import problem as opt_problem
from ocp.optimize import solve as opt
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.result import OptimizeResult
from ocp.optimize.solve import optimize

EXAMPLE = json.loads((Path(__file__).resolve().parents[2] / "examples" / "reversal.json").read_text())
# the paper-rig preset's constants, typed here (an oracle does not read the code it checks)
J, B, C_TAU, C_F, K_T, K_E, R, L = 2.71e-5, 5.31e-5, 2.2e-6, 1.4e-4, 0.0573, 0.0573, 5.0, 0.002
V_MAX, I_MAX = 12.0, 1.0


def _free(volts: float):
    return lambda _t, x: [(K_T * x[1] - B * x[0] - C_TAU * x[0] * abs(x[0])) / J, (volts - R * x[1] - K_E * x[0]) / L]


def _held(_t, x):
    return [(-K_T * I_MAX - B * x[0] - C_TAU * x[0] * abs(x[0])) / J]


def _until(fun, x0, event) -> tuple[float, np.ndarray]:
    def ev(_t, x):
        return event(x)

    ev.terminal = True  # type: ignore[attr-defined]
    sol = solve_ivp(fun, (0.0, 1.0), x0, events=ev, method="DOP853", rtol=1e-11, atol=1e-11)
    assert sol.t_events[0].size, "event not reached"
    return float(sol.t_events[0][0]), sol.y_events[0][0]


def _arc(w0: float, i0: float, w_switch: float, i_end: float) -> tuple[float, float]:
    """-V_MAX until i = -I_MAX, hold i = -I_MAX until w = w_switch, +V_MAX until i = i_end: (time, final speed)."""
    t1, x1 = _until(_free(-V_MAX), [w0, i0], lambda x: x[1] + I_MAX)
    t2, w2 = (_until(_held, [x1[0]], lambda x: x[0] - w_switch)[0], w_switch) if x1[0] > w_switch else (0.0, x1[0])
    t3, x3 = _until(_free(V_MAX), [w2, -I_MAX], lambda x: x[1] - i_end)
    # on the held arc the voltage R i + k_e w stays inside the limits
    assert abs(-R * I_MAX + K_E * w0) < V_MAX and abs(-R * I_MAX + K_E * w2) < V_MAX
    return t1 + t2 + t3, float(x3[0])


def oracle_min_time(continuous_voltage: bool, thrust: float = 0.4) -> float:
    """Minimum time [s] of the +thrust -> -thrust reversal from rest to rest (see module doc)."""
    w0 = math.sqrt(thrust / C_F)
    i0 = (B * w0 + C_TAU * w0 * w0) / K_T  # steady current at w0; -i0 at -w0
    if not continuous_voltage:
        ws = brentq(lambda s: _arc(w0, i0, s, -i0)[1] + w0, -w0 + 1e-6, 0.0, xtol=1e-12)
        return _arc(w0, i0, ws, -i0)[0]
    w1 = brentq(lambda s: _arc(w0, i0, s, 0.0)[1], 1e-6, 0.99 * w0, xtol=1e-12)  # reach w = 0 with i = 0
    w2 = brentq(lambda s: _arc(0.0, 0.0, s, -i0)[1] + w0, -w0 + 1e-6, -1e-3, xtol=1e-12)
    return _arc(w0, i0, w1, 0.0)[0] + _arc(0.0, 0.0, w2, -i0)[0]


def test_oracle_is_a_feasible_reversal_and_the_continuous_voltage_one_is_slower() -> None:
    """The oracle's own sanity: it ends where it should (checked inside), and the reversal that must pass
    through i = V = 0 at w = 0 cannot be faster than the unconstrained one."""
    bounded, smooth = oracle_min_time(False), oracle_min_time(True)
    assert 0.03 < bounded < smooth < 0.06
    # the held arc dominates: time >= (speed change) J / (k_t I_MAX + drag), drag >= 0 on the whole reversal
    assert bounded > 2.0 * math.sqrt(0.4 / C_F) * J / (K_T * I_MAX + B * 60 + C_TAU * 60**2)


@pytest.mark.slow
@pytest.mark.parametrize("regularity", ["bounded", "continuous-voltage"])
def test_min_time_converges_with_the_mesh_to_the_independent_solve(regularity: str) -> None:
    """Mesh refinement: the reported minimum time is within 0.5 % of the oracle, the error bound it reports
    covers its distance to the oracle, and it came from doubling meshes whose durations fall toward it."""
    m = mission_from_mapping({**EXAMPLE, "objective": "min-time", "regularity": regularity, "time_limit_s": 120.0})
    r = optimize(m)
    v = r.verification
    truth = oracle_min_time(regularity == "continuous-voltage")
    assert r.source == "optimized", r.reason
    assert v["min_time_converged"], v["min_time_note"]
    assert abs(v["min_time_s"] - truth) <= 5e-3 * truth
    # the verified answer respects the limits (within PATH_TOLERANCE), so it cannot beat the infimum by more
    assert v["min_time_s"] >= truth * (1.0 - 2e-3)
    assert v["min_time_s"] - truth <= v["min_time_error_bound_s"]
    mesh = v["min_time_mesh"]
    assert [row["intervals"] for row in mesh] == [120 * 2**k for k in range(len(mesh))] and len(mesh) >= 2
    assert mesh[-1]["min_time_s"] == v["min_time_s"] == pytest.approx(r.arrays["t"][-1], rel=1e-12)
    # the objective is the duration (the conditioning term is below 1e-6 of it)
    assert r.solver["objective"] == pytest.approx(v["min_time_s"] / 2.0, rel=1e-6)
    assert v["analytic_min_time_s"] > v["min_time_s"]


@pytest.mark.parametrize("regularity", ["bounded", "continuous-voltage"])
def test_min_time_smoothing_term_does_not_move_the_optimum(regularity: str, monkeypatch: pytest.MonkeyPatch) -> None:
    """One mesh, one IPOPT solve (no limit back-off): the objective is the duration over the desired length (2 s)
    plus less than 1e-6 of it, and the same program without the smoothing term (weight 0) gives the same
    duration to 1e-5 (IPOPT's own precision here: "acceptable" stops at tol 1e-4 on the scaled NLP)."""
    m = mission_from_mapping({**EXAMPLE, "objective": "min-time", "regularity": regularity,
                              "collocation": {"intervals": 60}, "time_limit_s": 60.0})
    problem = opt_problem.problem_for(m)
    r = opt.solve_problem(problem, opt_data.problem_data(problem), warm=False)
    assert isinstance(r, OptimizeResult) and r.source == "optimized", r.reason
    duration = r.arrays["t"][-1]
    assert 0.0 <= r.solver["objective"] - duration / 2.0 <= 1e-6 * duration / 2.0
    monkeypatch.setitem(opt_data.WEIGHTS, "min-time", (0.0, 1.0, 0.0, 0.0, 0.0))
    bare = opt.solve_problem(problem, opt_data.problem_data(problem), warm=False)
    assert isinstance(bare, OptimizeResult) and bare.source == "optimized", bare.reason
    assert bare.solver["objective"] == pytest.approx(bare.arrays["t"][-1] / 2.0, rel=1e-12)
    assert duration == pytest.approx(bare.arrays["t"][-1], rel=1e-5)
    assert 0.9 * oracle_min_time(False) < duration < 1.2 * oracle_min_time(False)


def test_summary_reports_no_bound_after_one_mesh_and_the_last_change_after_two() -> None:
    r = opt.optimize_mesh(mission_from_mapping({**EXAMPLE, "objective": "min-time", "collocation": {"intervals": 40}}))
    one = min_time.summary(r, [(40, 0.052)], "", None)
    assert one["min_time_error_bound_s"] is None and not one["min_time_converged"] and one["min_time_note"]
    two = min_time.summary(r, [(40, 0.053), (80, 0.052)], "", 0.09)
    assert two["min_time_error_bound_s"] == pytest.approx(0.001) and not two["min_time_converged"]
    three = min_time.summary(r, [(40, 0.053), (80, 0.0520), (160, 0.0519)], "", 0.09)
    assert three["min_time_converged"] and three["min_time_s"] == 0.0519 and three["min_time_note"] == ""


def test_a_fallback_never_reports_the_mission_length_as_a_minimum_time() -> None:
    """0.05 A cannot hold the initial 0.4 N (it needs 0.16 A): the answer is the analytic fallback, whose
    duration is the mission's 2 s within its retiming bounds (the fallback stretches time to keep the limits,
    issue #12), not a minimum; min_time_s must be None and the note must say why."""
    m = mission_from_mapping({**EXAMPLE, "objective": "min-time", "limits": {"voltage": 12.0, "current": 0.05}})
    r = optimize(m)
    assert r.source == "analytic-fallback"
    assert 2.0 * m.retiming.min_stretch - 1e-9 <= r.arrays["t"][-1] <= 2.0 * m.retiming.max_stretch + 1e-9
    v = r.verification
    assert v["min_time_s"] is None and v["min_time_error_bound_s"] is None and not v["min_time_converged"]
    assert "fallback" in v["min_time_note"] and v["min_time_mesh"] == []


def test_refinement_doubles_the_mesh_the_solve_really_uses() -> None:
    """8 intervals over 2 phases would be 4 per phase, below the 8-per-phase minimum: the first mesh is 16, then
    32, 64, ... (doubling the mission's 8 to 16 would re-solve the same mesh and report a false convergence)."""
    m = mission_from_mapping({**EXAMPLE, "objective": "min-time", "collocation": {"intervals": 8},
                              "time_limit_s": 60.0})
    v = optimize(m).verification
    sizes = [row["intervals"] for row in v["min_time_mesh"]]
    assert sizes[0] == 16 and sizes == [16 * 2**k for k in range(len(sizes))] and len(sizes) >= 2
    times = [row["min_time_s"] for row in v["min_time_mesh"]]
    assert all(abs(a - b) > 0.0 for a, b in itertools.pairwise(times))
