"""The FastAPI application factory.

``create_app(settings)`` builds the app; nothing runs until the lifespan starts, which opens the
job store (after taking its lock: one server per database; recovering items a dead server left
running), starts the solver and fallback worker processes, connects to Dask when configured, and
starts the batch runner -- and undoes all of it on shutdown. No request's computation runs in the
server process. A route
whose core backend is not installed is not registered (see :func:`service.tasks.available_tasks`).

Run with ``thrustshape serve`` or ``uvicorn --factory service.app:app_from_env``.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager
from pathlib import Path
from typing import Any, cast

from fastapi import Depends, FastAPI
from fastapi.openapi.docs import get_redoc_html, get_swagger_ui_html
from fastapi.responses import FileResponse, HTMLResponse, JSONResponse
from starlette.exceptions import HTTPException

from service.api import openapi, problems
from service.api.deps import require_api_key
from service.api.logging import RequestId, TaskLog, logged_lifespan
from service.api.middleware import ApiKeyGate, BodyLimit
from service.api.routes import batches, compare, health, info, model_check, page, references
from service.api.routes import stream as stream_route
from service.batches import BatchRunner
from service.checkjobs import CheckJobRunner, CheckJobStore
from service.dask_runner import DaskRunner
from service.jobs import JobStore, StoreLocked, lock_store
from service.settings import Settings
from service.tasks import TaskSet, available_tasks, fallback_mission
from service.workers import Runner, WorkerPool

log = logging.getLogger("thrustshape.service")

#: the small fallback each fallback worker runs once at start-up
_WARM_FALLBACK = {"reason": "warm-up", "mission": {"name": "warm-up", "segments": [
    {"kind": "hold", "duration": 0.1, "thrust": 0.2}, {"kind": "reversal", "duration": 0.2, "to": -0.2}]}}
_FORM_SLACK = 512 * 1024  # multipart framing and the non-file fields of a model-check upload [bytes]


def _lifespan(settings: Settings, tasks: TaskSet) -> Any:
    @asynccontextmanager
    async def lifespan(app: FastAPI) -> AsyncIterator[None]:
        try:
            lock = lock_store(settings.db_path)
        except StoreLocked as exc:
            log.error("%s", exc)
            raise
        store = JobStore(settings.db_path, busy_timeout=settings.store_busy_timeout_s)
        recovered = store.recover()
        if recovered:
            log.info("resuming %d batch items left running by a previous server", recovered)
        preload = ("ocp.reference.analytic", "ocp.reference.fallback", "ocp.optimize.mission", "service.tasks",
                   *tasks.extra_preload)
        pool = WorkerPool(settings.workers, settings.queue_size, settings.retry_after_s, preload=preload,
                          build_limit=settings.solver_build_limit_s, niceness=settings.solver_niceness,
                          memory_mib=settings.worker_memory_mb)
        # the analytic fallback runs in its own processes: killable, and never queued behind the solves
        fallback_pool = WorkerPool(settings.fallback_workers, settings.queue_size + settings.workers,
                                   settings.retry_after_s,
                                   preload=("ocp.reference.analytic", "ocp.reference.fallback",
                                            "ocp.reference.fallback_answer", "service.tasks",
                                            *(("ocp.optimize.problem",) if tasks.batch_key else ())),
                                   memory_mib=settings.worker_memory_mb)
        dask = await DaskRunner.connect(settings.dask_address) if settings.dask_address else None
        runner: Runner = dask if dask is not None else pool
        logged = cast(Runner, TaskLog(runner, tasks))  # one log line per batch item, like every request's task
        batch_runner = None if tasks.batch_item is None else BatchRunner(
            store, logged, tasks.batch_item, concurrency=settings.workers, timeout=settings.batch_item_timeout_s,
            attempts=settings.batch_attempts, key=tasks.batch_key, key_runner=fallback_pool,
            lookahead=settings.batch_lookahead,
            group_s=settings.batch_write_group_s)
        check_jobs = None if tasks.model_check is None else CheckJobRunner(  # model checks as jobs (progress)
            CheckJobStore(store), cast(Runner, TaskLog(pool, tasks)), tasks.model_check,
            timeout=settings.batch_item_timeout_s, attempts=settings.batch_attempts,
            max_pending=settings.workers + settings.queue_size, retry_after=settings.retry_after_s)
        app.state.settings, app.state.tasks, app.state.store = settings, tasks, store
        app.state.check_jobs = check_jobs
        app.state.pool, app.state.batches, app.state.fallback_pool = pool, batch_runner, fallback_pool
        # start-up off the first requests; a fallback worker also runs one small fallback (imports, caches)
        warming = [asyncio.create_task(pool.warm()),
                   # (the real fallback, not the task set's: a test's hanging task must not hang the warm-up)
                   asyncio.create_task(fallback_pool.warm(fallback_mission, _WARM_FALLBACK) if tasks.fallback
                                       else fallback_pool.warm())]
        if batch_runner is not None:
            batch_runner.start()
        if check_jobs is not None:
            check_jobs.resume()
        try:
            yield
        finally:
            for w in warming:
                w.cancel()
            if batch_runner is not None:
                await batch_runner.close()
            if check_jobs is not None:
                await check_jobs.close()
            if dask is not None:
                await dask.close()
            pool.close()
            fallback_pool.close()
            store.close()
            lock.close()

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
    # the key gate runs before the body limit and the routes: no body is read for a request without the key
    key = settings.api_key.get_secret_value().encode() if settings.api_key is not None else None
    app.add_middleware(ApiKeyGate, key=key, public=frozenset({"/healthz", "/"}),
                       public_prefixes=("/static/", DOCS_ASSETS_URL))
    app.add_middleware(RequestId)  # outermost: a 401, a 413 and an unexpected 500 carry the request id too
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


DOCS_ASSETS = Path(__file__).resolve().parent / "docs_assets"
DOCS_ASSETS_URL = "/docs/assets/"
_ASSET_TYPES = {".js": "text/javascript; charset=utf-8", ".css": "text/css; charset=utf-8", ".png": "image/png"}


def _docs(app: FastAPI) -> None:
    """OpenAPI at ``/openapi.json``, Swagger UI at ``/docs`` and ReDoc at ``/redoc`` (behind the API key when
    one is set); their scripts and styles come from the package (``service/docs_assets``, pinned versions),
    never from a CDN, so the docs work offline."""

    @app.get("/openapi.json", include_in_schema=False, dependencies=[Depends(require_api_key)])
    async def openapi() -> JSONResponse:
        return JSONResponse(app.openapi())

    @app.get("/docs", include_in_schema=False, dependencies=[Depends(require_api_key)])
    async def docs() -> HTMLResponse:
        return get_swagger_ui_html(openapi_url="/openapi.json", title="thrustshape API",
                                   swagger_js_url=DOCS_ASSETS_URL + "swagger-ui-bundle.js",
                                   swagger_css_url=DOCS_ASSETS_URL + "swagger-ui.css",
                                   swagger_favicon_url=DOCS_ASSETS_URL + "favicon-32x32.png")

    @app.get("/redoc", include_in_schema=False, dependencies=[Depends(require_api_key)])
    async def redoc() -> HTMLResponse:
        return get_redoc_html(openapi_url="/openapi.json", title="thrustshape API",
                              redoc_js_url=DOCS_ASSETS_URL + "redoc.standalone.js",
                              redoc_favicon_url=DOCS_ASSETS_URL + "favicon-32x32.png", with_google_fonts=False)

    @app.get(DOCS_ASSETS_URL + "{name}", include_in_schema=False)
    async def docs_asset(name: str) -> FileResponse:
        files = {p.name: p for p in DOCS_ASSETS.iterdir() if p.suffix in _ASSET_TYPES} if DOCS_ASSETS.is_dir() else {}
        if name not in files:
            raise HTTPException(404, f"no docs asset {name!r}")
        return FileResponse(files[name], media_type=_ASSET_TYPES[files[name].suffix],
                            headers={"Cache-Control": "public, max-age=86400"})


def app_from_env() -> FastAPI:
    """Factory for ``uvicorn --factory``: settings from ``THRUSTSHAPE_*`` variables."""
    return create_app(Settings())
