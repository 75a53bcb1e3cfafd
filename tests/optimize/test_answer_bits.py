"""Issue 14 (the time of an answer outside the solver): the faster paths give the former numbers bit for bit.

Oracles: the former implementations, kept here as they were on main at 8bc3704 (the guess's rate limit as a loop
over numpy scalars; the answer's plan evaluated by scipy's ``BSpline`` per phase and order, its command grid by
``np.union1d``).
"""

import numpy as np

from bench.user_missions import user_missions
from ocp.optimize import flat, flat_solve
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import Problem, problem_for

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
