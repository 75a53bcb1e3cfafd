"""Health: ``GET /healthz`` (never needs the API key): the job store, the batch runner and the workers.

200 with ``status: "ok"`` when all is well; 503 with ``status: "degraded"`` and the reason when the store
fails (file gone, not answering) or the batch runner is retrying store writes or has stopped.
"""

from __future__ import annotations

import asyncio

from fastapi import APIRouter, Request, Response

from service.jobs import StoreUnavailable
from service.schemas import Health, RunnerPublic, StorePublic, WorkersPublic

router = APIRouter(tags=["health"])


@router.get("/healthz", response_model=Health, summary="Liveness and readiness: store, batch runner, workers",
            responses={503: {"model": Health, "description": "degraded: the store or the batch runner fails"}})
async def healthz(request: Request, response: Response) -> Health:
    state = request.app.state
    try:
        await asyncio.to_thread(state.store.ping)
        store = StorePublic(ok=True)
    except StoreUnavailable as exc:
        store = StorePublic(ok=False, detail=str(exc))
    runner = None
    if getattr(state, "batches", None) is not None:
        h = state.batches.health()
        runner = RunnerPublic(state=h.state, unsaved=h.unsaved, inflight=h.inflight, last_error=h.last_error)
    workers, fallback = (WorkersPublic(size=p.size, alive=p.alive(), ready=p.ready(), pending=p.pending)
                         for p in (state.pool, state.fallback_pool))
    ok = store.ok and (runner is None or runner.state == "running")
    if not ok:
        response.status_code = 503
    return Health(status="ok" if ok else "degraded", store=store, runner=runner, workers=workers,
                  fallback_workers=fallback)
