"""``POST /v1/compare``: analytic ``A sin^(2q+1)`` shapes vs the optimised reference for a mission."""

from __future__ import annotations

from typing import Annotated, Any

from fastapi import APIRouter, Query
from pydantic import Field

from service.api.deps import PoolDep, SettingsDep, TasksDep, check_mission_limits
from service.api.problems import error_responses
from service.core_models import ComparePublic
from service.errors import FeatureUnavailable
from service.schemas import MissionRequest

router = APIRouter(prefix="/v1", tags=["compare"])
_ERRORS = error_responses(401, 413, 422, 501, 503, 504)


@router.post("/compare", response_model=ComparePublic, responses=_ERRORS,
             summary="Compare the analytic family with the optimised reference (peaks, energy, regularity)")
async def compare(mission: MissionRequest, settings: SettingsDep, pool: PoolDep, tasks: TasksDep,
                  qs: Annotated[list[Annotated[int, Field(ge=0, le=10)]] | None,
                                Query(max_length=8, description="q values of the analytic shapes "
                                                                "(repeat: ?qs=0&qs=2); default 0, 1, 2, 3")] = None
                  ) -> Any:
    check_mission_limits(mission, settings)
    if tasks.compare is None:  # the route is only registered when the backend exists
        raise FeatureUnavailable("comparison", "ocp.optimize.compare")
    payload = {"mission": mission.model_dump(mode="json"), "qs": list(dict.fromkeys(qs)) if qs else None}
    return await pool.run(tasks.compare, payload, settings.task_timeout_s)
