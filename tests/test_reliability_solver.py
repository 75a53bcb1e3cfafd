"""The solver cache is not keyed by the time limit (issue #12, finding 7): one built program serves every
``time_limit_s``; the limit is enforced per call by the IPOPT iteration callback (``User_Requested_Stop``)."""

from __future__ import annotations

import json
import time
from pathlib import Path

from ocp import collocation as col
from ocp.mission import mission_from_mapping
from ocp.optimize import optimize, problem_for, solver_options

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())


def test_one_program_serves_every_time_limit_and_each_limit_holds() -> None:
    short = mission_from_mapping({**EXAMPLE, "time_limit_s": 0.02})
    long = mission_from_mapping({**EXAMPLE, "time_limit_s": 60.0})
    a, b = problem_for(short), problem_for(long)
    assert a.structure == b.structure
    prog = col.solver_for(a.plant, a.structure, solver_options())  # built once (or already cached)
    assert col.solver_for(b.plant, b.structure, solver_options()) is prog
    t0 = time.perf_counter()
    stopped = optimize(short)
    assert stopped.source == "analytic-fallback" and stopped.reason.startswith("solver time limit reached")
    assert stopped.solver["status"] == "User_Requested_Stop" and stopped.solver["solve_time_s"] < 0.5
    assert stopped.verification["path_ok"] and time.perf_counter() - t0 < 10.0
    done = optimize(long)
    assert done.source == "optimized" and done.solver["build_time_s"] < 0.5  # the same cached program
    assert col.solver_for(b.plant, b.structure, solver_options()) is prog
