"""Optimiser tests: every claim checked against an independent oracle (scipy Radau simulation of the
exact returned command, the closed-form analytic family, Theorem 1 on the desired profile)."""

import itertools
import json
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp.errors import MissionError
from ocp.optimize import collocation as col
from ocp.optimize.collocation import ipopt_options
from ocp.optimize.data import problem_data
from ocp.optimize.mission import mission_from_mapping, sample_segments, segment_samples
from ocp.optimize.problem import problem_for
from ocp.optimize.result import OptimizeResult, SolverProgram
from ocp.optimize.solve import optimize, solve_problem
from ocp.reference.fallback import design_sin
from ocp.reference.fallback_answer import analytic_fallback
from ocp.theory.crossings import classify_profile
from ocp.theory.reversal import UNBOUNDED, ReversalRegularity
from tests.motor_ode import dc_motor_ode

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())
SINE = {"name": "sine", "limits": {"voltage": 12.0, "current": 1.0},
        "segments": [{"kind": "sine", "duration": 2.0, "amplitude": 0.4, "period": 2.0}]}


def _scipy_replay(result, params, t_eval):
    """Independent oracle: scipy Radau on the exact held command (knots, values) of a result, one solve per held
    piece: each piece is a smooth problem (a smooth voltage returned as a held command has hundreds of pieces, and
    one solve across all their jumps took minutes). Returns (current (M,), thrust (M,)) on ``t_eval`` (M,)."""
    ct, cv = result.arrays["command_t"], result.arrays["command"]
    rhs, jac = dc_motor_ode(params)

    x = np.array([result.arrays["omega"][0], result.arrays["current"][0]], float)
    out = np.empty((2, t_eval.size))
    cuts = np.union1d(np.clip(ct, t_eval[0], t_eval[-1]), [t_eval[0], t_eval[-1]])
    for a, b in itertools.pairwise(cuts):
        volts = float(cv[min(max(int(np.searchsorted(ct, 0.5 * (a + b), side="right")) - 1, 0), cv.size - 1)])
        inside = (t_eval >= a) & (t_eval < b)
        sol = solve_ivp(rhs, (a, b), x, method="Radau", jac=jac, args=(volts,), t_eval=np.append(t_eval[inside], b),
                        rtol=1e-9, atol=1e-10)
        assert sol.success
        out[:, inside] = sol.y[:, :-1]
        x = sol.y[:, -1]
    out[:, -1] = x  # the state at the last knot, t_eval[-1]
    return out[1], params.c_f * out[0] * np.abs(out[0])


def test_linear_crossing_becomes_reproducible_within_limits():
    m = mission_from_mapping(SINE)
    t_d, f_d = m.desired()
    assert classify_profile(t_d, f_d, c_f=m.motor().c_f).current == UNBOUNDED  # the request is not reproducible
    r = optimize(m)
    assert r.source == "optimized", r.reason
    fine = np.linspace(0.0, r.arrays["t"][-1], 8001)
    current, thrust = _scipy_replay(r, m.motor(), fine)
    # limits hold everywhere on a fine grid, not only at the collocation nodes (0.1 % rounding allowed)
    assert np.max(np.abs(current)) <= 1.0 * 1.001
    assert np.max(np.abs(r.arrays["command"])) <= 12.0 * 1.001
    # the simulated thrust reproduces the returned thrust (stated tolerance: 0.2 % of the peak)
    f_ret = np.interp(fine, r.arrays["t"], r.arrays["thrust"])
    assert np.max(np.abs(thrust - f_ret)) <= 2e-3 * 0.4
    assert r.verification["thrust_rms_error"] <= 1e-3 * 0.4
    assert [c["exponent"] for c in r.crossings] == [2.0]
    assert abs(r.crossings[0]["t"] - 1.0) < 0.05


def test_continuous_voltage_gives_zero_current_and_voltage_at_crossings():
    m = mission_from_mapping({**EXAMPLE, "regularity": "continuous-voltage"})
    r = optimize(m)
    assert r.source == "optimized", r.reason
    assert r.crossings
    for c in r.crossings:
        assert c["exponent"] == 6.0
        assert c["current"] == 0.0 and c["voltage"] == 0.0  # the plan, exactly
        # the simulated response under the returned command agrees near the crossing
        assert abs(np.interp(c["t"], r.arrays["t"], r.arrays["current"])) <= 1e-2 * m.limits.current
        k = np.searchsorted(r.arrays["t"], c["t"])
        assert np.max(np.abs(r.arrays["voltage"][k - 1:k + 1])) <= 1e-2 * m.limits.voltage
    # the voltage is continuous: no jump between output samples beyond what its bounded slew allows
    dv = np.abs(np.diff(r.arrays["voltage"]))
    assert np.max(dv) < 0.2 * m.limits.voltage


def _sin5_mission(period: float) -> dict:
    t = np.linspace(0.0, period, 801)
    f = 0.4 * np.sin(2 * np.pi * t / period) ** 5
    return {"name": "sin5", "limits": {"voltage": 12.0, "current": 1.0}, "regularity": "continuous-voltage",
            "retiming": {"min_stretch": 1.0, "max_stretch": 3.0}, "profile": {"t": t.tolist(), "thrust": f.tolist()}}


def test_retiming_stretches_only_as_much_as_needed(rig):
    t_min = design_sin(rig, 1.0, 12.0, ReversalRegularity.CONTINUOUS_VOLTAGE, amplitude=0.4).profile.period
    slow = optimize(mission_from_mapping(_sin5_mission(1.3 * t_min)))
    assert slow.source == "optimized" and max(slow.stretch) <= 1.0 + 1e-3
    fast = optimize(mission_from_mapping(_sin5_mission(0.6 * t_min)))
    assert fast.source == "optimized", fast.reason
    # stretched, but never more than what makes the exact sin^5 fit the limits (an analytic upper bound)
    assert max(fast.stretch) > 1.05
    assert max(fast.stretch) <= (t_min / (0.6 * t_min)) * 1.02
    assert fast.verification["max_abs_current"] <= 1.001 and fast.verification["max_abs_voltage"] <= 12.012


def test_unmeetable_limits_give_fallback_with_reason():
    m = mission_from_mapping({**EXAMPLE, "limits": {"voltage": 12.0, "current": 0.05}})
    r = optimize(m)
    assert r.source == "analytic-fallback"
    assert "limits" in r.reason
    assert r.to_dict()["reason"] == r.reason


def test_solver_time_limit_gives_fallback():
    m = mission_from_mapping({**EXAMPLE, "time_limit_s": 1e-4, "collocation": {"intervals": 400}})
    r = optimize(m)
    assert r.source == "analytic-fallback" and "time limit" in r.reason


@pytest.mark.parametrize(
    ("patch", "field"),
    [
        ({"retiming": {"min_stretch": 2.0, "max_stretch": 1.0}}, "retiming"),
        ({"limits": {"current": -1.0}}, "limits.current"),
        ({"regularity": "bounded", "min_crossing_order": 6}, "min_crossing_order"),
        ({"objective": "fastest"}, "objective"),
        ({"collocation": {"intervals": 10**6}}, "collocation.intervals"),
        ({"surprise": 1}, "surprise"),
        ({"params": {"J": 1.0}}, "params.B"),
        ({"segments": [{"kind": "hold", "duration": -1.0, "thrust": 0.1}]}, "segments.0.duration"),
    ],
)
def test_bad_missions_name_the_field(patch, field):
    with pytest.raises(MissionError) as ei:
        mission_from_mapping({**EXAMPLE, **patch})
    assert ei.value.field == field


def test_profile_must_be_monotonic():
    with pytest.raises(MissionError) as ei:
        mission_from_mapping({"profile": {"t": [0.0, 2.0, 1.0], "thrust": [0.1, 0.2, 0.3]}})
    assert ei.value.field == "profile" and "increasing" in ei.value.reason


def test_structure_is_built_once_and_warm_start_helps():
    m = mission_from_mapping(EXAMPLE)
    problem = problem_for(m)
    first = optimize(m, program=SolverProgram.RADAU)
    prog = col.solver_for(problem.plant, problem.structure, ipopt_options(m.time_limit_s))
    again = optimize(m, program=SolverProgram.RADAU)
    assert again.solver["build_time_s"] < 0.05 <= first.solver["build_time_s"] + 0.05
    assert col.solver_for(problem.plant, problem.structure, ipopt_options(m.time_limit_s)) is prog
    # the reported parts of the call are disjoint pieces of it
    parts = [again.solver[k] for k in ("setup_time_s", "build_time_s", "solve_time_s", "verify_time_s")]
    assert min(parts[:1] + parts[2:]) > 0 and sum(parts) <= again.total_time_s
    warm = optimize(mission_from_mapping({**EXAMPLE, "limits": {"voltage": 12.0, "current": 0.98}}), warm=True,
                    program=SolverProgram.RADAU)
    assert warm.source == "optimized"
    assert warm.solver["iterations"] <= again.solver["iterations"]


def test_torque_plant_respects_torque_bound(rig):
    m = mission_from_mapping({**EXAMPLE, "plant": "torque", "limits": {"torque": 0.02}})
    r = optimize(m)
    assert r.source == "optimized", r.reason
    assert np.max(np.abs(r.arrays["torque"])) * rig.J <= 0.02 * 1.001
    assert r.verification["thrust_rms_error"] <= 1e-3 * 0.4


def test_torque_channel_fallback_and_min_time_respect_the_torque_bound(rig):
    """The torque channel's analytic answers are sized to its torque bound, not to the DC motor's current and
    voltage: the fallback's torque, recomputed from its speed by finite differences (J w' + c_tau w|w|), reaches
    the bound and stays within it; min-time reports the fastest torque-bounded sin^(2q+1) and beats it."""
    m = mission_from_mapping({**EXAMPLE, "plant": "torque", "limits": {"torque": 0.02}})
    fb = analytic_fallback(m, "test")
    t, w = fb.arrays["t"], fb.arrays["omega"]
    torque = rig.J * np.gradient(w, t) + rig.c_tau * w * np.abs(w)
    assert 0.02 * 0.99 <= np.max(np.abs(torque)) <= 0.02 * 1.002
    smooth = np.abs(t - fb.crossings[0]["t"]) > 2e-3  # w ~ |s|^1.5 there: a difference quotient is no oracle
    np.testing.assert_allclose(fb.arrays["torque"][smooth] * rig.J, torque[smooth], atol=2e-4)
    assert fb.verification["path_ok"] and fb.verification["max_abs_torque"] <= 0.02 * 1.001
    assert np.isfinite(fb.verification["thrust_rms_error"]) and fb.verification["thrust_rms_error"] < 1e-3 * 0.4

    r = optimize(mission_from_mapping({**EXAMPLE, "plant": "torque", "limits": {"torque": 0.02},
                                       "objective": "min-time"}))
    v = r.verification
    assert r.source == "optimized" and v["max_abs_torque"] <= 0.02 * 1.001
    assert v["analytic_min_time_s"] is not None and v["min_time_s"] <= v["analytic_min_time_s"]
    sine = design_sin(rig, 1.0, 12.0, ReversalRegularity.BOUNDED, amplitude=0.4, voltage_driven=False,
                      torque_limit=0.02).profile
    assert v["analytic_min_time_s"] == pytest.approx(0.5 * sine.period)
    ts = np.linspace(0.0, sine.period, 20001)
    ws = np.sign(f := sine.thrust(ts)[0]) * np.sqrt(np.abs(f) / rig.c_f)
    peak = np.max(np.abs(rig.J * np.gradient(ws, ts) + rig.c_tau * ws * np.abs(ws)))
    assert 0.02 * 0.995 <= peak <= 0.02 * 1.002  # the shortest period whose torque meets the bound


def test_min_time_is_no_slower_than_the_fastest_analytic_reversal():
    m = mission_from_mapping({**EXAMPLE, "objective": "min-time"})
    r = optimize(m)
    assert r.source == "optimized", r.reason
    v = r.verification
    assert v["analytic_min_time_s"] is not None
    assert v["min_time_s"] <= v["analytic_min_time_s"]
    assert abs(r.arrays["thrust"][-1] + 0.4) < 5e-3 and abs(r.arrays["thrust"][0] - 0.4) < 1e-6
    assert v["max_abs_current"] <= 1.001


@pytest.mark.parametrize("regularity", ["bounded", "continuous-voltage"])
def test_min_time_starts_from_the_fastest_analytic_reversal(rig, regularity):
    """The cold guess of a min-time solve is the analytic fallback: its duration is half the period of the
    fastest sin^(2q+1) within the limits and its speed is that sine's static inverse at the collocation
    times; from there IPOPT converges in fewer iterations than from the desired profile's static inverse."""
    m = mission_from_mapping({**EXAMPLE, "objective": "min-time", "regularity": regularity})
    problem = problem_for(m)
    data = problem_data(problem)
    lay, sc = col.layout(2, problem.structure.intervals, data.scales.x.size), data.scales.x
    design = design_sin(rig, 1.0, 12.0, ReversalRegularity(regularity), amplitude=0.4)
    h = data.x0[lay.stretch] * problem.phases.durations
    assert h == pytest.approx([0.25 * design.profile.period] * 2, rel=1e-12)
    taus = ((np.arange(problem.structure.intervals)[:, None] + col.TAU[None, 1:]) / problem.structure.intervals)
    t = np.concatenate([h[0] * taus.ravel(), h[0] + h[1] * taus.ravel()])
    thrust = 0.4 * np.cos(2 * np.pi * t / design.profile.period) ** (2 * design.profile.q + 1)  # sin(x + pi/2)
    omega = np.sign(thrust) * np.sqrt(np.abs(thrust) / rig.c_f)
    guess = data.x0[lay.xc[:, :, :, 0]].ravel() * sc[0]
    inner = np.ones(t.size, bool)
    inner[problem.structure.intervals * col.DEGREE - 1] = False  # the crossing node is fixed to 0 by a bound
    np.testing.assert_allclose(guess[inner], omega[inner], rtol=1e-9, atol=1e-9)

    static = problem_data(problem, analytic_start=False)
    assert np.all(static.x0[lay.stretch] == 1.0)
    analytic_run, static_run = solve_problem(problem, data, False), solve_problem(problem, static, False)
    assert analytic_run.source == static_run.source == "optimized"
    assert analytic_run.solver["objective"] <= static_run.solver["objective"] * (1 + 1e-6)
    assert analytic_run.solver["iterations"] < static_run.solver["iterations"]


def test_overshoot_between_nodes_is_removed_by_a_local_back_off():
    """A step reversal at the current limit: the plan keeps |i| <= I at the nodes, the simulated current
    overshoots between them; the bounds are tightened only around the overshoot, and that costs no more
    objective than tightening them everywhere by the same factor. (The plain DC motor's current is now held
    between the nodes by construction, ocp/optimize/path_limits.py; a calibrated plant, here with a small
    brush drop, is where the back-off still does that work.)"""
    rig = json.loads(Path("ocp/presets/paper-rig.json").read_text())
    m = mission_from_mapping({
        "name": "step", "limits": {"voltage": 12.0, "current": 1.0},
        "params": {**{k: v for k, v in rig.items() if k != "notes"}, "effects": {"brush_drop": {"v_b": 0.2}}},
        "retiming": {"min_stretch": 1.0, "max_stretch": 2.0},
        "segments": [{"kind": "hold", "duration": 0.5, "thrust": 0.4},
                     {"kind": "reversal", "duration": 0.2, "to": -0.4, "shape": "step"},
                     {"kind": "hold", "duration": 0.5, "thrust": -0.4}]})
    problem = problem_for(m)
    plan = solve_problem(problem, problem_data(problem), False)
    assert isinstance(plan, OptimizeResult), plan  # solved (an Unsolved has no verification)
    assert plan.verification["max_abs_current"] > 1.001
    r = optimize(m)
    assert r.source == "optimized" and r.solver["backoff_rounds"] >= 1
    assert r.verification["max_abs_current"] <= 1.001 and r.verification["max_abs_voltage"] <= 12.0 * 1.001
    assert 0 < r.solver["backoff_intervals"] <= problem.structure.n_phases * problem.structure.intervals // 10
    uniform = solve_problem(problem, problem_data(problem, r.solver["limit_backoff"]), False)
    assert r.solver["objective"] <= uniform.solver["objective"] * (1 + 1e-9)


def test_cli_optimize_and_compare(tmp_path):
    out = tmp_path / "ref.csv"
    run = subprocess.run([sys.executable, "-m", "clients.cli", "optimize", "examples/reversal.json", "--json",
                          "--out", str(out)], capture_output=True, text=True, check=True)
    payload = json.loads(run.stdout)
    for key in ("source", "status", "reason", "solve_time_s", "verification", "crossings", "t", "thrust",
                "thrust_desired", "omega", "theta", "current", "voltage"):
        assert key in payload
    assert out.read_text().splitlines()[0] == "t,thrust,thrust_desired,omega,theta,current,voltage"
    plot = tmp_path / "cmp.svg"
    run = subprocess.run([sys.executable, "-m", "clients.cli", "compare", "examples/reversal.json", "--json",
                          "--plot", str(plot)], capture_output=True, text=True, check=True)
    table = json.loads(run.stdout)["table"]
    assert table[0]["label"] == "optimized" and len(table) == 5
    assert table[0]["within_limits"] and not table[1]["within_limits"]  # sin^1 is unbounded
    assert table[1]["peak_current_a"] is None  # inf is not JSON: reported as null
    assert plot.stat().st_size > 1000
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({**EXAMPLE, "limits": {"voltage": -3}}))
    run = subprocess.run([sys.executable, "-m", "clients.cli", "optimize", str(bad)], capture_output=True, text=True)
    assert run.returncode == 1 and "limits.voltage" in run.stderr
    assert math.isfinite(payload["solve_time_s"])
    torque = tmp_path / "torque.json"
    torque.write_text(json.dumps({**EXAMPLE, "plant": "torque", "limits": {"torque": 0.02}, "objective": "min-time"}))
    text = subprocess.run([sys.executable, "-m", "clients.cli", "optimize", str(torque)], capture_output=True,
                          text=True, check=True).stdout
    times = re.search(r"minimum transition ([\d.]+) ms; fastest analytic .* limits ([\d.]+) ms", text)
    assert times is not None and float(times[1]) < float(times[2]), text
    assert re.search(r"\|torque\| 0\.02 N m", text) and "IPOPT iterations" in text


@pytest.mark.parametrize("durations", [(0.5, 0.2, 0.5), (0.0004, 1.2345, 0.001), (3.0,)])
def test_segment_samples_counts_what_sample_segments_makes(durations):
    segs = mission_from_mapping({"segments": [{"kind": "hold", "duration": d, "thrust": 0.1} for d in durations]})
    assert segs.segments is not None
    assert segment_samples(segs.segments) == sample_segments(segs.segments)[0].size


def test_untrusted_missions_cannot_name_files(tmp_path):
    f = tmp_path / "rig.json"
    f.write_text(json.dumps({"J": 2.71e-5, "B": 5.31e-5, "c_tau": 2.2e-6, "c_f": 1.4e-4, "k_t": 0.0573,
                             "k_e": 0.0573, "R": 5.0, "L": 0.002}))
    assert mission_from_mapping({**EXAMPLE, "params": str(f)}).motor().R == 5.0  # trusted: a file is fine
    with pytest.raises(MissionError) as ei:
        mission_from_mapping({**EXAMPLE, "params": str(f)}, allow_files=False)
    assert ei.value.field == "params" and "files are not read" in ei.value.reason
    assert mission_from_mapping({**EXAMPLE, "params": "paper-rig"}, allow_files=False).motor().R == 5.0


def test_compare_sends_every_shape_and_keeps_unbounded_samples_out_of_json():
    from ocp.optimize.compare import compare

    d = compare(mission_from_mapping(EXAMPLE)).to_dict()
    json.dumps(d, allow_nan=False)  # strict JSON
    labels = [c["label"] for c in d["candidates"]]
    assert labels[0] == "optimized" and len(labels) == 5
    sin1 = d["candidates"][1]
    assert None in sin1["current"] and None in sin1["voltage"]  # the linear crossing's ideal command
    sin5 = d["candidates"][3]
    assert None not in sin5["voltage"] and len(sin5["t"]) == len(sin5["thrust"])
