"""Service logging: request ids, one line per request and per task, start/stop, under uvicorn's config.

* :class:`RequestId` (pure ASGI middleware): takes ``X-Request-ID`` from the request (1-128 of
  ``[A-Za-z0-9._:-]``) or makes one, returns it on the answer, and holds it in a context variable
  for the request; :class:`RequestIdFilter` writes it into every record a handler sees
  (``request_id=-`` outside a request), so every line a request causes carries it.
* :class:`TaskLog` wraps a worker pool: one ``logfmt`` line per task on ``thrustshape.tasks``:
  ``task id=... kind=optimize duration_ms=... outcome=ok|invalid|timeout|failed|busy|error``.
* :func:`log_config`: the ``logging.config.dictConfig`` that ``thrustshape serve`` hands uvicorn:
  uvicorn's own loggers plus ``thrustshape.*`` (so app lines such as "resuming batch items" are not
  dropped), every format with the request id. :func:`ensure_handler` covers a plain
  ``uvicorn --factory service.app:app_from_env``, whose config knows nothing of ``thrustshape``.

Level of the ``thrustshape`` loggers: ``THRUSTSHAPE_LOG_LEVEL`` (default ``INFO``).
"""

from __future__ import annotations

import json
import logging
import os
import re
import time
import uuid
from collections.abc import AsyncIterator, Callable
from contextlib import AbstractAsyncContextManager, asynccontextmanager
from contextvars import ContextVar
from dataclasses import fields
from typing import Any

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from ocp.errors import ThrustshapeError
from service.api.problems import PROBLEM

request_id: ContextVar[str] = ContextVar("thrustshape_request_id", default="-")

HEADER = "X-Request-ID"
_VALID = re.compile(r"[A-Za-z0-9._:-]{1,128}")
FORMAT = "%(asctime)s %(levelname)s %(name)s: %(message)s request_id=%(request_id)s"
ACCESS_FORMAT = '%(asctime)s %(levelname)s %(name)s: %(client_addr)s - "%(request_line)s" %(status_code)s ' \
                'request_id=%(request_id)s'

http_log = logging.getLogger("thrustshape.http")
task_log = logging.getLogger("thrustshape.tasks")
service_log = logging.getLogger("thrustshape.service")


def level() -> str:
    return os.environ.get("THRUSTSHAPE_LOG_LEVEL", "INFO").upper()


class RequestIdFilter(logging.Filter):
    """Adds ``record.request_id`` (the current request's, or ``-``)."""

    def filter(self, record: logging.LogRecord) -> bool:
        if not hasattr(record, "request_id"):
            record.request_id = request_id.get()
        return True


class RequestId:
    """Accept or make the request id, answer it in ``X-Request-ID``, log one line per request."""

    def __init__(self, app: ASGIApp) -> None:
        self.app = app

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        given = dict(scope.get("headers") or []).get(HEADER.lower().encode(), b"").decode("latin-1")
        rid = given if _VALID.fullmatch(given) else uuid.uuid4().hex
        token = request_id.set(rid)
        start, status, sent = time.perf_counter(), 500, False

        async def send_with_id(msg: Message) -> None:
            nonlocal status, sent
            if msg["type"] == "http.response.start":
                status, sent = int(msg["status"]), True
                msg["headers"] = [*msg.get("headers", []), (HEADER.lower().encode(), rid.encode())]
            await send(msg)

        try:
            await self.app(scope, receive, send_with_id)
        except Exception:  # a bug, not an input error: problem+json 500 (traceback in the log), not text/plain
            http_log.exception("unexpected error on %s %s", scope.get("method"), scope.get("path"))
            if sent:  # too late for an error answer: let the server close the connection
                raise
            await _internal_error(send_with_id, rid)
        finally:
            http_log.info("request method=%s path=%s status=%d duration_ms=%.1f", scope.get("method"),
                          scope.get("path"), status, 1e3 * (time.perf_counter() - start))
            request_id.reset(token)


async def _internal_error(send: Send, rid: str) -> None:
    body = json.dumps({"type": "about:blank", "title": "Internal server error", "status": 500,
                       "detail": f"unexpected server error; quote request id {rid} when reporting it",
                       "request_id": rid}).encode()
    await send({"type": "http.response.start", "status": 500,
                "headers": [(b"content-type", PROBLEM.encode()), (b"content-length", str(len(body)).encode())]})
    await send({"type": "http.response.body", "body": body})


def _outcome(exc: BaseException | None) -> str:
    if exc is None:
        return "ok"
    if isinstance(exc, ThrustshapeError):
        return "invalid"
    return {"TaskTimeout": "timeout", "TaskFailed": "failed", "QueueFull": "busy"}.get(type(exc).__name__, "error")


class TaskLog:
    """A worker pool (anything with ``async run(fn, payload, timeout, **kw)``) that logs each task."""

    def __init__(self, pool: Any, tasks: Any) -> None:
        self._pool, self._tasks = pool, tasks

    def _kind(self, fn: Callable[..., Any]) -> str:
        for f in fields(self._tasks):
            if getattr(self._tasks, f.name) is fn:
                return f.name
        return getattr(fn, "__name__", "task")

    async def run(self, fn: Callable[..., Any], payload: Any, timeout: float, **kw: Any) -> Any:
        tid, start, error = uuid.uuid4().hex[:12], time.perf_counter(), None
        try:
            return await self._pool.run(fn, payload, timeout, **kw)
        except BaseException as exc:
            error = exc
            raise
        finally:
            outcome = _outcome(error)
            task_log.log(logging.WARNING if outcome in ("timeout", "failed", "error") else logging.INFO,
                         "task id=%s kind=%s duration_ms=%.1f outcome=%s%s", tid, self._kind(fn),
                         1e3 * (time.perf_counter() - start), outcome,
                         "" if error is None else f" error={type(error).__name__}")

    def __getattr__(self, name: str) -> Any:
        return getattr(self._pool, name)


def logged_lifespan(inner: Callable[[Any], AbstractAsyncContextManager[None]],
                    describe: Callable[[], str]) -> Callable[[Any], AbstractAsyncContextManager[None]]:
    """The app's lifespan with a ``start ...`` line once it is up and a ``stop`` line at shutdown."""

    @asynccontextmanager
    async def lifespan(app: Any) -> AsyncIterator[None]:
        ensure_handler()
        async with inner(app):
            service_log.info("start %s", describe())
            try:
                yield
            finally:
                service_log.info("stop")

    return lifespan


def ensure_handler() -> None:
    """Give ``thrustshape.*`` a stderr handler (with the request id) when nothing would print its
    records: no handler on it or on the root logger (e.g. under uvicorn's default config)."""
    root, ours = logging.getLogger(), logging.getLogger("thrustshape")
    if ours.level == logging.NOTSET:
        ours.setLevel(level())
    if ours.handlers or root.handlers:
        return
    handler = logging.StreamHandler()
    handler.addFilter(RequestIdFilter())
    handler.setFormatter(logging.Formatter(FORMAT))
    ours.addHandler(handler)


def log_config(uvicorn_level: str = "info") -> dict[str, Any]:
    """``dictConfig`` for ``uvicorn.run(log_config=...)``: uvicorn's loggers and ``thrustshape.*``."""
    lvl = uvicorn_level.upper()
    handler = {"class": "logging.StreamHandler", "stream": "ext://sys.stderr", "filters": ["request_id"]}
    return {
        "version": 1, "disable_existing_loggers": False,
        "filters": {"request_id": {"()": "service.api.logging.RequestIdFilter"}},
        "formatters": {"default": {"format": FORMAT},  # uvicorn's AccessFormatter fills client_addr, request_line
                       "access": {"()": "uvicorn.logging.AccessFormatter", "fmt": ACCESS_FORMAT, "use_colors": False}},
        "handlers": {"default": {**handler, "formatter": "default"}, "access": {**handler, "formatter": "access"}},
        "loggers": {
            "uvicorn": {"handlers": ["default"], "level": lvl, "propagate": False},
            "uvicorn.error": {"level": lvl},
            "uvicorn.access": {"handlers": ["access"], "level": lvl, "propagate": False},
            "thrustshape": {"handlers": ["default"], "level": level(), "propagate": False},
        },
    }
