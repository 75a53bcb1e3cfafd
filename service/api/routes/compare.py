"""``POST /v1/compare``: analytic ``A sin^(2q+1)`` shapes vs the optimised reference for a mission."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter

from ocp.errors import MissionError
from service.api.deps import PoolDep, SettingsDep, TasksDep, check_mission_limits
from service.api.problems import error_responses
from service.schemas import MissionRequest

router = APIRouter(prefix="/v1", tags=["compare"])
_ERRORS = error_responses(401, 413, 422, 503, 504)


@router.post("/compare", response_model=dict[str, Any], responses=_ERRORS,
             summary="Compare the analytic family with the optimised reference (peaks, energy, regularity)")
async def compare(mission: MissionRequest, settings: SettingsDep, pool: PoolDep, tasks: TasksDep) -> Any:
    check_mission_limits(mission, settings)
    if tasks.compare is None:  # the route is only registered when the backend exists
        raise MissionError("route", "comparison is not available on this server")
    return await pool.run(tasks.compare, mission.model_dump(mode="json"), settings.task_timeout_s)
