"""Issue 14: a corner of the desired thrust inside a phase (a ramp's ends) gets the flat program the spans to
follow it, so that its objective is equal or better than the Radau program's (rtol 1e-3, the benchmark's).

Oracle: the Radau program's answer to the same mission on one evaluator (``objective_of``); with 20 spans the
flat answer's objective was 4.6x it.
"""

import math

from ocp.optimize import flat_solve
from ocp.optimize.evaluate import objective_of
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for
from ocp.optimize.result import SolverProgram
from ocp.optimize.solve import optimize_mesh


def _reversal(shape: str) -> dict:
    """``bench/optimizer.py``'s classic ``ramp`` (``shape="ramp"``): hold 0.4 N, reverse in 0.6 s, hold -0.4 N."""
    return {"limits": {"voltage": 12.0, "current": 1.0},
            "segments": [{"kind": "hold", "duration": 0.5, "thrust": 0.4},
                         {"kind": "reversal", "duration": 0.6, "to": -0.4, "shape": shape},
                         {"kind": "hold", "duration": 0.5, "thrust": -0.4}]}


def test_a_ramp_has_corners_a_cosine_reversal_none():
    """The ramp's ends lie inside its two phases (the crossing splits it): doubled spans; the cosine's not."""
    ramp, cosine = (problem_for(mission_from_mapping(_reversal(s))) for s in ("ramp", "cosine"))
    base = max(flat_solve.SPANS[0], min(math.ceil(ramp.structure.intervals / flat_solve.SPANS_PER_INTERVALS),
                                        flat_solve.SPANS[1]))
    assert flat_solve.has_corner(ramp) and not flat_solve.has_corner(cosine)
    assert flat_solve.structure_of(ramp).spans == min(2 * base, flat_solve.SPANS_CORNER)
    assert flat_solve.structure_of(cosine).spans == base


def test_ramp_flat_objective_equal_or_better_than_radau():
    mission = mission_from_mapping(_reversal("ramp"))
    problem = problem_for(mission)
    fast = optimize_mesh(mission)
    radau = optimize_mesh(mission, program=SolverProgram.RADAU)
    assert fast.solver.program == SolverProgram.FLAT
    assert objective_of(problem, fast) <= objective_of(problem, radau) * (1 + 1e-3)
