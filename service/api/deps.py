"""Request dependencies (``Annotated`` aliases): settings, worker pool, job store, tasks, access, limits.

Everything comes from ``request.app.state``, filled by the lifespan in :func:`service.app.create_app`.
"""

from __future__ import annotations

import hmac
from typing import Annotated, cast

from fastapi import Depends, Request
from fastapi.security import HTTPAuthorizationCredentials, HTTPBearer
from starlette.exceptions import HTTPException

from ocp.errors import MissionError
from ocp.optimize.mission import OUTPUT_RATE, Mission, segment_samples
from ocp.theory.crossings import sign_change_times
from service.api.logging import TaskLog
from service.batches import BatchRunner
from service.jobs import JobStore
from service.settings import Settings
from service.tasks import TaskSet
from service.workers import WorkerPool

#: fewest collocation intervals the optimiser gives one phase (ocp.optimize.solve.MIN_INTERVALS_PER_PHASE, lower one)
MIN_INTERVALS_PER_PHASE = 8

_bearer = HTTPBearer(auto_error=False, description="API key from THRUSTSHAPE_API_KEY (only when the server sets one)")


def get_settings(request: Request) -> Settings:
    return request.app.state.settings


def get_pool(request: Request) -> WorkerPool:
    """The worker pool, each task it runs logged (one line: id, kind, duration, outcome)."""
    return cast(WorkerPool, TaskLog(request.app.state.pool, request.app.state.tasks))


def get_store(request: Request) -> JobStore:
    return request.app.state.store


def get_tasks(request: Request) -> TaskSet:
    return request.app.state.tasks


def get_batches(request: Request) -> BatchRunner:
    return request.app.state.batches


SettingsDep = Annotated[Settings, Depends(get_settings)]
PoolDep = Annotated[WorkerPool, Depends(get_pool)]
StoreDep = Annotated[JobStore, Depends(get_store)]
TasksDep = Annotated[TaskSet, Depends(get_tasks)]
BatchesDep = Annotated[BatchRunner, Depends(get_batches)]


async def require_api_key(settings: SettingsDep,
                          cred: Annotated[HTTPAuthorizationCredentials | None, Depends(_bearer)]) -> None:
    """401 unless the server has no key or the request carries ``Authorization: Bearer <key>``."""
    if settings.api_key is None:
        return
    key = settings.api_key.get_secret_value().encode()
    if cred is None or not hmac.compare_digest(cred.credentials.encode(), key):
        raise HTTPException(401, "missing or wrong API key (Authorization: Bearer <key>)",
                            headers={"WWW-Authenticate": "Bearer"})


def check_mission_limits(mission: Mission, settings: Settings, prefix: str = "") -> None:
    """Server caps beyond the core's: profile samples, returned samples and collocation intervals (422 naming
    the field), checked before any work starts."""
    n = len(mission.profile.t) if mission.profile is not None else 0
    if n > settings.max_profile_samples:
        raise MissionError(f"{prefix}profile.t",
                           f"{n} samples; this server accepts at most {settings.max_profile_samples}")
    if mission.segments is not None:
        n = segment_samples(mission.segments)  # counted, not sampled: this runs on the event loop
        if n > settings.max_profile_samples:
            raise MissionError(f"{prefix}segments", f"sample to {n} points; this server accepts at most "
                                                    f"{settings.max_profile_samples}")
    out = mission.span() * mission.retiming.max_stretch * OUTPUT_RATE + 1.0  # returned samples, at most
    if out > settings.max_reference_samples:
        raise MissionError(f"{prefix}retiming.max_stretch", f"a {mission.span():.4g} s profile stretched up to "
                                                            f"{mission.retiming.max_stretch:g}x gives {out:.4g} "
                                                            f"samples; this server returns at most "
                                                            f"{settings.max_reference_samples}")
    phases = 1 + len(sign_change_times(*mission.desired()))  # at most max_profile_samples: cheap
    if MIN_INTERVALS_PER_PHASE * phases > settings.max_intervals:
        where = "profile.thrust" if mission.profile is not None else "segments"
        raise MissionError(f"{prefix}{where}", f"{phases - 1} reversals need at least {MIN_INTERVALS_PER_PHASE} "
                                               f"collocation intervals each ({MIN_INTERVALS_PER_PHASE * phases}); "
                                               f"this server accepts at most {settings.max_intervals}")
    if mission.collocation.intervals > settings.max_intervals:
        raise MissionError(f"{prefix}collocation.intervals", f"{mission.collocation.intervals} intervals; this "
                                                             f"server accepts at most {settings.max_intervals}")
