"""The FastAPI application factory.

``create_app(settings)`` builds the app; nothing runs until the lifespan starts, which opens the
job store (recovering items a dead server left running), starts the worker processes, connects to
Dask when configured, and starts the batch runner -- and undoes all of it on shutdown. A route
whose core backend is not installed is not registered (see :func:`service.tasks.available_tasks`).

Run with ``thrustshape serve`` or ``uvicorn --factory service.app:app_from_env``.
"""

from __future__ import annotations

import logging
from collections.abc import AsyncIterator
from concurrent.futures import ThreadPoolExecutor
from contextlib import asynccontextmanager
from typing import Any

from fastapi import Depends, FastAPI
from fastapi.openapi.docs import get_swagger_ui_html
from fastapi.responses import HTMLResponse, JSONResponse

from service.api import openapi, problems
from service.api.deps import require_api_key
from service.api.logging import RequestId, logged_lifespan
from service.api.middleware import BodyLimit
from service.api.routes import batches, compare, health, info, model_check, page, references
from service.api.routes import stream as stream_route
from service.batches import BatchRunner
from service.jobs import JobStore
from service.settings import Settings
from service.tasks import TaskSet, available_tasks
from service.workers import DaskRunner, Runner, WorkerPool

log = logging.getLogger("thrustshape.service")

_FORM_SLACK = 512 * 1024  # multipart framing and the non-file fields of a model-check upload [bytes]


def _lifespan(settings: Settings, tasks: TaskSet) -> Any:
    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        store = JobStore(settings.db_path)
        recovered = store.recover()
        if recovered:
            log.info("resuming %d batch items left running by a previous server", recovered)
        preload = ("ocp.analytic", "ocp.fallback", "ocp.mission", *tasks.extra_preload)
        pool = WorkerPool(settings.workers, settings.queue_size, settings.retry_after_s, preload=preload)
        dask = await DaskRunner.connect(settings.dask_address) if settings.dask_address else None
        runner: Runner = dask if dask is not None else pool
        fallback_threads = ThreadPoolExecutor(max_workers=2, thread_name_prefix="thrustshape-fallback")
        batch_runner = None if tasks.batch_item is None else BatchRunner(
            store, runner, tasks.batch_item, concurrency=settings.workers, timeout=settings.batch_item_timeout_s,
            attempts=settings.batch_attempts)
        app.state.settings, app.state.tasks, app.state.store = settings, tasks, store
        app.state.pool, app.state.batches, app.state.fallback_threads = pool, batch_runner, fallback_threads
        if batch_runner is not None:
            batch_runner.start()
        try:
            yield
        finally:
            if batch_runner is not None:
                await batch_runner.close()
            if dask is not None:
                await dask.close()
            pool.close()
            fallback_threads.shutdown(wait=False, cancel_futures=True)
            store.close()

    return lifespan


def create_app(settings: Settings | None = None, tasks: TaskSet | None = None) -> FastAPI:
    """Build the app; ``settings`` default to the environment, ``tasks`` to the installed core backends."""
    settings = settings if settings is not None else Settings()
    tasks = tasks if tasks is not None else available_tasks()
    app = FastAPI(
        title="thrustshape",
        summary="Reproducible thrust references for bidirectional propellers",
        version=info._version(),
        lifespan=logged_lifespan(_lifespan(settings, tasks), lambda: _describe(settings)),
        docs_url=None, redoc_url=None, openapi_url=None,
        generate_unique_id_function=openapi.operation_id,
    )
    problems.install(app)
    openapi.install(app)
    # a log upload may exceed max_body_bytes: its own limit, plus room for the small form fields
    app.add_middleware(BodyLimit, max_bytes=settings.max_body_bytes,
                       uploads={model_check.PREFIX: (settings.max_upload_bytes + _FORM_SLACK, "log")})
    app.add_middleware(RequestId)  # outermost: a 413 and an unexpected 500 carry the request id too
    guard = [Depends(require_api_key)]
    app.include_router(health.router)
    app.include_router(page.router)
    app.include_router(stream_route.router)  # WebSocket: checks the API key itself (browsers send no headers)
    app.include_router(info.router, dependencies=guard)
    app.include_router(references.analytic_router, dependencies=guard)
    if tasks.optimize is not None and tasks.fallback is not None:
        app.include_router(references.optimize_router, dependencies=guard)
    if tasks.compare is not None:
        app.include_router(compare.router, dependencies=guard)
    if tasks.batch_item is not None:
        app.include_router(batches.router, dependencies=guard)
    if tasks.model_check is not None:
        app.include_router(model_check.router, dependencies=guard)
    _docs(app)
    app.state.settings, app.state.tasks = settings, tasks
    return app


def _describe(s: Settings) -> str:
    """The ``start`` log line's fields."""
    return (f"version={info._version()} workers={s.workers} queue={s.queue_size} db={s.db_path} "
            f"batch_backend={'dask' if s.dask_address else 'local'} api_key={'set' if s.api_key else 'none'}")


def _docs(app: FastAPI) -> None:
    """OpenAPI at ``/openapi.json`` and Swagger UI at ``/docs``, behind the API key when one is set."""

    @app.get("/openapi.json", include_in_schema=False, dependencies=[Depends(require_api_key)])
    async def openapi() -> JSONResponse:
        return JSONResponse(app.openapi())

    @app.get("/docs", include_in_schema=False, dependencies=[Depends(require_api_key)])
    async def docs() -> HTMLResponse:
        return get_swagger_ui_html(openapi_url="/openapi.json", title="thrustshape API")


def app_from_env() -> FastAPI:
    """Factory for ``uvicorn --factory``: settings from ``THRUSTSHAPE_*`` variables."""
    return create_app(Settings())
