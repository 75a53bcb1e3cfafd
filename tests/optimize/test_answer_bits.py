"""Issue 14 (the time of an answer outside the solver): the faster paths give the former numbers bit for bit.

Oracles: the former implementations, kept here as they were on main at 8bc3704 (the guess's rate limit as a loop
over numpy scalars; the answer's plan evaluated by scipy's ``BSpline`` per phase and order, its command grid by
``np.union1d``).
"""

import numpy as np
import pytest
from scipy.interpolate import BSpline

from bench.user_missions import user_missions
from ocp.errors import MissionError
from ocp.optimize import flat, flat_solve
from ocp.optimize.mission import Profile, mission_from_mapping
from ocp.optimize.problem import Problem, problem_for
from ocp.optimize.result import SolverProgram, SolverStats
from tests.optimize.test_flat import solved

REVERSAL = {"name": "rev", "limits": {"voltage": 12.0, "current": 1.0},
            "segments": [{"kind": "hold", "duration": 0.5, "thrust": 0.4},
                         {"kind": "reversal", "duration": 1.0, "to": -0.4, "shape": "cosine"},
                         {"kind": "hold", "duration": 0.5, "thrust": -0.4}]}


def _problems() -> list[Problem]:
    return [problem_for(mission_from_mapping(spec)) for spec in [REVERSAL, *user_missions()]]


def _former_rate_limited(problem: Problem, speed: np.ndarray, j: int) -> np.ndarray:
    mp, phases = problem.mission.motor(), problem.phases
    torque = mp.k_t * problem.mission.limits.current
    t = phases.bounds[j] + flat.points(speed.size // flat.GAUSS)["quad"] * phases.durations[j]
    out = speed.copy()
    prev_t, prev = (phases.bounds[j], 0.0) if j > 0 else (t[0], out[0])
    for n in range(out.size):
        rate = flat_solve.GUESS_CURRENT * max(torque - mp.B * prev - mp.c_tau * prev**2, 0.0) / mp.J
        prev = out[n] = min(out[n], prev + rate * (t[n] - prev_t))
        prev_t = t[n]
    nxt_t, nxt = (t[-1], out[-1]) if j == phases.signs.size - 1 else (phases.bounds[j + 1], 0.0)
    for n in range(out.size - 1, -1, -1):
        rate = flat_solve.GUESS_CURRENT * (torque + mp.B * nxt + mp.c_tau * nxt**2) / mp.J
        nxt = out[n] = min(out[n], nxt + rate * (nxt_t - t[n]))
        nxt_t = t[n]
    return out


def test_the_guess_rate_limit_on_python_floats_is_the_former_loop():
    """Per phase of the reversal and the six user missions, on the static inverse and on 40 random speeds (which
    the limit clips often): the same array to the last bit (``**`` is C's pow for a Python float and a numpy
    scalar alike)."""
    rng = np.random.default_rng(4)
    for problem in _problems():
        st = flat_solve.structure_of(problem)
        quad = flat.points(st.spans)["quad"]
        for j in range(problem.phases.signs.size):
            t = problem.phases.bounds[j] + quad * problem.phases.durations[j]
            static = np.sqrt(np.abs(np.interp(t, problem.t_desired, problem.f_desired)) / problem.mission.motor().c_f)
            for speed in [static, *rng.uniform(0.0, 2.0 * float(np.max(static)), (40, static.size))]:
                np.testing.assert_array_equal(flat_solve._rate_limited(problem, speed, j),
                                              _former_rate_limited(problem, speed, j))


def _former_states(plan: flat_solve.FlatPlan, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The plan's (states (2, M), voltage (M,)) at ``t`` (M,) as before: scipy's BSpline per phase and order."""
    P = plan.coef.shape[0]
    j = np.clip(np.searchsorted(plan.phase_edges, t, side="right") - 1, 0, P - 1)
    h = np.diff(plan.phase_edges)
    tau = np.clip((t - plan.phase_edges[j]) / h[j], 0.0, 1.0)
    w = [np.zeros_like(t) for _ in range(3)]
    for k in range(P):
        sel = j == k
        chain = [BSpline(plan.knots, plan.coef[k], flat.DEGREE)]
        for _ in range(2):
            chain.append(chain[-1].derivative())
        for r in range(3):
            w[r][sel] = chain[r](tau[sel]) / h[k] ** r
    cur, volts = flat.drive([*w, np.zeros_like(t)], dict(plan.constants), plan.signs[j], 0)
    return np.vstack([w[0], cur]), volts


def _former_held_command(plan: flat_solve.FlatPlan, t: np.ndarray, dv: float) -> tuple[np.ndarray, np.ndarray]:
    frac = np.arange(flat_solve.SUBSTEPS) / flat_solve.SUBSTEPS
    grid = np.union1d(np.append((t[:-1, None] + frac[None, :] * np.diff(t)[:, None]).ravel(), t[-1]),
                      plan.phase_edges)
    dt = np.diff(grid)
    v = _former_states(plan, 0.5 * (grid[:-1] + grid[1:]))[1]
    level = np.round(v / dv)
    cut = np.flatnonzero(np.diff(level) != 0) + 1
    at_edges = np.searchsorted(grid, plan.phase_edges[1:-1])
    starts = np.union1d(np.concatenate([[0], cut, at_edges]), []).astype(int)
    held = np.add.reduceat(v * dt, starts) / np.add.reduceat(dt, starts)
    return np.append(grid[starts], grid[-1]), held


@pytest.mark.parametrize("name", ["rev", "user-sine-1hz-b", "user-ramp-cv"])
def test_the_answer_is_the_former_evaluation_bit_for_bit(name: str):
    """A solved flat program packaged as an answer (the plan evaluated once at the command grid's midpoints, the
    output times and the reversals together, by the vectorised de Boor pass): the held command, the planned
    voltage on the output grid, the crossings' planned current and voltage and the reproduction error equal the
    former evaluation's (scipy per phase and order, three separate evaluations) to the last bit."""
    spec = next(s for s in [REVERSAL, *user_missions()] if s["name"] == name)
    problem, st, data, run = solved(spec)
    answer = flat_solve._answer(problem, st, run.x, data, SolverStats(program=SolverProgram.FLAT))
    plan = flat_solve.plan_of(problem, st, run.x, data)
    t = answer.arrays["t"]
    knots, held = _former_held_command(plan, t, flat_solve.COMMAND_DV * data.scales.u_lim)
    np.testing.assert_array_equal(answer.arrays["command_t"], knots)
    np.testing.assert_array_equal(answer.arrays["command"], np.append(held, held[-1]))
    x_plan, v_plan = _former_states(plan, t)
    np.testing.assert_array_equal(answer.arrays["voltage"], v_plan)
    err = answer.arrays["thrust"] - problem.plant.thrust([x_plan[0], x_plan[1]])
    assert answer.verification.thrust_rms_error == float(np.sqrt(np.mean(err**2)))
    x_cross, v_cross = _former_states(plan, plan.phase_edges[1:-1])
    assert [(c.current, c.voltage) for c in answer.crossings] == list(zip(x_cross[1], v_cross, strict=True))
    assert len(answer.crossings) == problem.phases.signs.size - 1 >= 1


def test_the_resolved_bounds_follow_a_copied_mission():
    """Mission.bounds() is kept per limits, profile and params: a copy with other limits, another profile or
    other motor constants gets its own (the default torque bound 4 c_tau F_peak / c_f follows all three)."""
    m = mission_from_mapping(REVERSAL)
    first = m.bounds()
    assert m.bounds() is first and first.torque == pytest.approx(4 * 2.2e-6 * 0.4 / 1.4e-4)
    tighter = m.model_copy(update={"limits": m.limits.model_copy(update={"current": 0.5})})
    assert tighter.bounds().current == 0.5 and m.bounds().current == 1.0
    t = np.linspace(0.0, 1.0, 11)
    sampled = m.model_copy(update={"segments": None,
                                   "profile": Profile(t=t.tolist(), thrust=(0.8 * np.cos(3 * t)).tolist())})
    assert sampled.bounds().torque == pytest.approx(4 * 2.2e-6 * 0.8 / 1.4e-4)
    weaker = m.model_copy(update={"params": {**m.motor().model_dump(), "c_f": 2.8e-4}})
    assert weaker.bounds().torque == pytest.approx(first.torque / 2)


def test_phase_signs_are_the_former_majority_vote():
    """Random profiles (sign runs of random lengths, zero samples, single-sample phases): the phases and their signs
    equal the former per-phase masks' majority vote."""
    from itertools import pairwise

    from ocp.optimize.problem import split_phases
    from ocp.theory.crossings import sign_change_times

    rng = np.random.default_rng(9)
    checked = 0
    for _ in range(300):
        n = int(rng.integers(5, 200))
        t = np.cumsum(rng.uniform(0.001, 0.01, n))
        f = np.repeat(rng.choice([-1.0, 1.0], n), rng.integers(1, 6, n))[:n] * rng.uniform(0.1, 1.0, n)
        f[rng.random(n) < 0.1] = 0.0
        if not np.any(f):
            continue
        try:
            phases = split_phases(t, f)
        except MissionError:  # reversals closer than the samples allow (refused either way)
            continue
        checked += 1
        bounds = np.array([t[0], *sign_change_times(t, f, 1e-12 * float(np.max(np.abs(f)))), t[-1]])
        former = []
        for a, b in pairwise(bounds):
            inside = f[(t > a) & (t < b)]
            s = np.sign(np.sum(np.sign(inside))) if inside.size else np.sign(np.interp(0.5 * (a + b), t, f))
            former.append(1.0 if s >= 0 else -1.0)
        np.testing.assert_array_equal(phases.bounds, bounds)
        np.testing.assert_array_equal(phases.signs, former)
    assert checked >= 200
