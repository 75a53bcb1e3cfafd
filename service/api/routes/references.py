"""References: ``POST /v1/references/analytic`` and ``POST /v1/references/optimize``."""

from __future__ import annotations

import asyncio
from typing import Any, cast

from fastapi import APIRouter, Request

from ocp.errors import MissionError
from service.api.answers import json_answer
from service.api.deps import PoolDep, SettingsDep, TasksDep, check_mission_limits
from service.api.logging import TaskLog
from service.api.problems import error_responses
from service.errors import DeadlineExceeded, FeatureUnavailable, TaskFailed, TaskTimeout
from service.schemas import AnalyticRequest, DesignRequest, MissionRequest, OptimizePublic, ReferencePublic
from service.workers import PHASES, WorkerPool

_ERRORS = error_responses(401, 413, 422, 503, 504)
_OPTIMIZE_ERRORS = error_responses(401, 413, 422, 501, 503, 504)

analytic_router = APIRouter(prefix="/v1/references", tags=["references"])
optimize_router = APIRouter(prefix="/v1/references", tags=["references"])


@analytic_router.post("/analytic", response_model=ReferencePublic, responses=_ERRORS,
                      summary="Exact feedforward of an A sin^(2q+1) profile, or the analytic design within limits")
async def analytic(req: AnalyticRequest, settings: SettingsDep, pool: PoolDep, tasks: TasksDep) -> Any:
    duration = req.duration if req.duration is not None else req.period
    if duration is not None:
        n = duration * req.rate + 1.0  # float: may overflow to inf, never raises
        if not n <= settings.max_reference_samples:
            raise MissionError("rate", f"duration x rate gives {n:.4g} samples; this server returns at most "
                                       f"{settings.max_reference_samples}")
    elif isinstance(req, DesignRequest) and req.rate > settings.max_reference_samples:
        raise MissionError("rate", f"at most {settings.max_reference_samples} Hz")
    payload = {"request": req.model_dump(mode="json"), "max_samples": settings.max_reference_samples}
    return await pool.run(tasks.analytic, payload, settings.task_timeout_s)


_SOLVER_OUT = {"queue": "no solver worker was free within {:.3g} s (queue)",
               "start-up": "the solver worker process was still starting after {:.3g} s (start-up)",
               "build": "the solver for this mission's structure was still being built after {:.3g} s (build; "
                        "the worker finishes and keeps it for the next request)",
               "run": "the solver did not finish within {:.3g} s (run)"}


@optimize_router.post("/optimize", response_model=OptimizePublic, responses=_OPTIMIZE_ERRORS,
                      summary="Optimal reference for a mission, or the analytic fallback when the deadline is near")
async def optimize(mission: MissionRequest, request: Request, settings: SettingsDep, pool: PoolDep,
                   tasks: TasksDep) -> Any:
    """One deadline ``min(optimize_deadline_s, time_limit_s + optimize_grace_s)`` covers everything: the wait
    for a solver worker, its start-up, the solve, then the analytic fallback in its own worker process. The
    solver part ends ``fallback_reserve_s`` before the deadline; if it runs out (its process is killed) or its
    process dies, the answer is the fallback with ``source = "analytic-fallback"`` and a ``reason`` that says
    which part ran out. A mission nothing within the limits reproduces is a 422 ``InfeasibleError``."""
    check_mission_limits(mission, settings)
    if tasks.optimize is None or tasks.fallback is None:  # routes are only registered with both
        raise FeatureUnavailable("optimisation", "ocp.optimize.solve")
    loop = asyncio.get_running_loop()
    total = min(settings.optimize_deadline_s, mission.time_limit_s + settings.optimize_grace_s)
    start = loop.time()
    solve_budget = max(total - settings.fallback_reserve_s, 0.0)
    payload = mission.model_dump(mode="json")
    try:
        return json_answer(OptimizePublic, await pool.run(tasks.optimize, payload, solve_budget,
                                                          deadline=start + solve_budget,
                                                          min_run=min(1.0, 0.5 * solve_budget)))
    except TaskTimeout as exc:
        reason = "deadline: " + _SOLVER_OUT[exc.phase].format(solve_budget)
    except TaskFailed as exc:
        reason = f"solver process failed: {exc.detail}"
    fallbacks = cast(WorkerPool, TaskLog(request.app.state.fallback_pool, tasks))
    detail = ""
    for _ in range(2):  # a fallback process that dies (killed, out of memory) gets one more try
        try:
            return json_answer(OptimizePublic, await fallbacks.run(tasks.fallback, {"mission": payload,
                                                                                   "reason": reason},
                                                                   total, deadline=start + total))
        except TaskTimeout as exc:
            raise DeadlineExceeded(total, f"{reason}; then the fallback ran out while "
                                          f"{PHASES[exc.phase]} ({exc.phase})") from None
        except TaskFailed as exc:
            detail = exc.detail
            if loop.time() >= start + total:
                break
    raise TaskFailed(f"{reason}; then the fallback process failed twice: {detail}")
