"""``GET /v1/info``: version, presets, effects, limits and which optional routes exist."""

from __future__ import annotations

import importlib.metadata

from fastapi import APIRouter

from ocp.model.effects import CATALOGUE
from ocp.model.params import PRESETS
from ocp.theory.reversal import ReversalRegularity
from service.api.deps import SettingsDep, TasksDep
from service.schemas import InfoPublic, LimitsPublic

router = APIRouter(prefix="/v1", tags=["info"])


def _version() -> str:
    try:
        return importlib.metadata.version("thrustshape")
    except importlib.metadata.PackageNotFoundError:
        return "0+unknown"


def effect_names() -> list[str]:
    """Names of the plant effects in the core's catalogue (``ocp.model.effects.CATALOGUE``)."""
    return sorted(CATALOGUE)


@router.get("/info", response_model=InfoPublic, summary="Version, presets, effects, limits")
async def info(settings: SettingsDep, tasks: TasksDep) -> InfoPublic:
    s = settings
    return InfoPublic(
        version=_version(), presets=list(PRESETS), effects=effect_names(),
        regularities=[r.value for r in ReversalRegularity],
        limits=LimitsPublic(max_body_bytes=s.max_body_bytes, max_profile_samples=s.max_profile_samples,
                            max_intervals=s.max_intervals, max_batch_missions=s.max_batch_missions,
                            max_reference_samples=s.max_reference_samples,
                            max_upload_bytes=s.max_upload_bytes, max_log_samples=s.max_log_samples,
                            optimize_deadline_s=s.optimize_deadline_s, task_timeout_s=s.task_timeout_s),
        features={"optimize": tasks.optimize is not None, "compare": tasks.compare is not None,
                  "batches": tasks.batch_item is not None, "model_check": tasks.model_check is not None},
        workers=s.workers, batch_backend="dask" if s.dask_address else "local",
    )
