"""The solver cache is not keyed by the time limit (issue #12, finding 7): one built program serves every
``time_limit_s``; the limit is enforced per call by the IPOPT iteration callback (``User_Requested_Stop``)."""

from __future__ import annotations

import asyncio
import json
import time
from pathlib import Path

from ocp.optimize import collocation as col
from ocp.optimize.collocation import solver_options
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.problem import problem_for
from ocp.optimize.solve import optimize

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())


def test_one_program_serves_every_time_limit_and_each_limit_holds() -> None:
    short = mission_from_mapping({**EXAMPLE, "time_limit_s": 0.0002})
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


def test_a_solve_stops_before_its_worker_would_be_killed() -> None:
    """In a worker, IPOPT stops ``SOLVE_MARGIN_S`` before the call's deadline whatever the mission's time limit:
    a solve that would outlast its call answers (the analytic fallback, "solver time limit reached") instead of
    having its process killed, and the process keeps its built solver."""
    from service.tasks import SOLVE_MARGIN_S, optimize_mission
    from service.workers import WorkerPool

    payload = {**EXAMPLE, "time_limit_s": 60.0}

    async def scenario() -> None:
        pool = WorkerPool(1, queue_size=0, retry_after=1, preload=("ocp.optimize.solve", "service.tasks"))
        try:
            first = await pool.run(optimize_mission, payload, timeout=120)  # builds and solves
            assert first["source"] == "optimized"
            pid = pool.pids()[0]
            t0 = time.monotonic()
            capped = await pool.run(optimize_mission, payload, timeout=SOLVE_MARGIN_S + 0.001)
            assert time.monotonic() - t0 < SOLVE_MARGIN_S + 0.5
            assert capped["source"] == "analytic-fallback" and capped["reason"].startswith("solver time limit")
            assert capped["solver"]["status"] == "User_Requested_Stop"
            assert capped["solver"]["build_time_s"] < 0.5 and pool.pids() == [pid]  # same process, cached solver
            again = await pool.run(optimize_mission, payload, timeout=120)
            assert again["source"] == "optimized" and pool.pids() == [pid]
        finally:
            pool.close()

    asyncio.run(scenario())
