"""The service's own errors: one tree, one handler, each class answering with its own status and title."""

from __future__ import annotations

import asyncio

import httpx
import pytest
from fastapi import FastAPI

from ocp.errors import MissionError
from service import errors
from service.api import problems
from service.api.problems import BodyTooLarge
from service.jobs import IdempotencyConflict, StoreUnavailable
from service.workers import QueueFull, TaskFailed, TaskTimeout

CASES: list[tuple[errors.ServiceError, int, str | None, str | None]] = [
    (errors.TooLarge("missions", "7 missions; at most 5"), 413, "missions", None),
    (BodyTooLarge(1024), 413, "body", None),
    (IdempotencyConflict("k", "b1"), 422, "Idempotency-Key", None),
    (errors.FeatureUnavailable("optimisation", "ocp.optimize.solve"), 501, "route", None),
    (TaskFailed("worker process died (exit code -9)"), 500, None, None),
    (QueueFull(3), 503, None, "3"),
    (StoreUnavailable("the job store does not answer"), 503, None, "5"),
    (TaskTimeout(2.0, "build"), 504, None, None),
    (errors.DeadlineExceeded(4.0, "the solver and then the fallback ran out"), 504, None, None),
]


def _answer(exc: BaseException) -> httpx.Response:
    """What an app with the service's handlers answers to a route that raises ``exc`` (in process)."""
    app = FastAPI()
    problems.install(app)

    @app.get("/boom")
    async def boom() -> None:
        raise exc

    async def get() -> httpx.Response:
        async with httpx.AsyncClient(transport=httpx.ASGITransport(app), base_url="http://test") as c:
            return await c.get("/boom")

    return asyncio.run(get())


def test_every_service_error_is_one_tree_and_the_old_import_paths_still_work() -> None:
    for exc, *_ in CASES:
        assert isinstance(exc, errors.ServiceError)
    # the classes the pool and the store raise are the tree's, not copies
    assert QueueFull is errors.QueueFull and StoreUnavailable is errors.StoreUnavailable
    assert TaskTimeout is errors.TaskTimeout and IdempotencyConflict is errors.IdempotencyConflict


@pytest.mark.parametrize(("exc", "status", "field", "retry_after"), CASES, ids=lambda c: type(c).__name__)
def test_one_handler_maps_each_class_to_its_status(exc: errors.ServiceError, status: int, field: str | None,
                                                   retry_after: str | None) -> None:
    r = _answer(exc)
    assert r.status_code == status
    assert r.headers["content-type"].startswith("application/problem+json")
    body = r.json()
    assert body["status"] == status and body["title"] == type(exc).title and body["detail"] == str(exc)
    assert body["error_type"] == type(exc).__name__
    assert body.get("field") == field
    assert r.headers.get("retry-after") == retry_after


def test_a_missing_backend_is_501_naming_it_never_a_422() -> None:
    body = _answer(errors.FeatureUnavailable("comparison", "ocp.optimize.compare")).json()
    assert body["status"] == 501 and body["field"] == "route"
    assert "ocp.optimize.compare" in body["reason"] and "not installed" in body["reason"]
    # the core's input errors keep their own handler (422 naming the field)
    r = _answer(MissionError("limits.current", "must be positive"))
    assert r.status_code == 422 and r.json()["field"] == "limits.current"
