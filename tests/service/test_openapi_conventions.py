"""The OpenAPI document is what client generators expect: a readable, unique operationId per
operation, every error response documented as ``application/problem+json`` with the Problem schema,
request-body examples that the API itself accepts; an unexpected exception answers problem+json 500
(not text/plain) and every answer carries an ``X-Request-ID``."""

from __future__ import annotations

import asyncio
import re
from typing import Any

import httpx
import pytest

from service.app import create_app
from service.schemas import BatchCreate, DesignRequest, MissionRequest, SinRequest
from service.settings import Settings

PROBLEM = "application/problem+json"


class InProcess:
    """GETs against the app in-process (no lifespan: these routes need neither workers nor the job store)."""

    def __init__(self, app: Any) -> None:
        self.app = app

    def get(self, path: str, headers: dict[str, str] | None = None) -> httpx.Response:
        async def go() -> httpx.Response:
            async with httpx.AsyncClient(transport=httpx.ASGITransport(app=self.app), base_url="http://t") as c:
                return await c.get(path, headers=headers)

        return asyncio.run(go())


@pytest.fixture(scope="module")
def app() -> Any:
    return create_app(Settings())


@pytest.fixture(scope="module")
def spec(app: Any) -> dict[str, Any]:
    r = InProcess(app).get("/openapi.json")
    assert r.status_code == 200
    return r.json()


def operations(spec: dict[str, Any]) -> list[tuple[str, str, dict[str, Any]]]:
    return [(m.upper(), p, op) for p, ops in spec["paths"].items() for m, op in ops.items()]


def test_every_operation_has_a_readable_unique_operation_id(spec: dict[str, Any]) -> None:
    ids = [op["operationId"] for _, _, op in operations(spec)]
    assert len(ids) >= 11 and len(set(ids)) == len(ids)
    for i in ids:  # a method name: snake_case words, no path fragments or HTTP verbs glued on
        assert re.fullmatch(r"[a-z]+(_[a-z]+){0,3}", i) and "v1" not in i and not i.endswith(("_post", "_get")), i
    by_path = {(m, p): op["operationId"] for m, p, op in operations(spec)}
    assert by_path[("POST", "/v1/references/optimize")] == "optimize_reference"
    assert by_path[("GET", "/v1/batches/{batch_id}/results")] == "get_batch_results"


def test_every_error_response_is_problem_json(spec: dict[str, Any]) -> None:
    problem = spec["components"]["schemas"]["Problem"]
    assert {"title", "status", "detail"} <= set(problem["required"]) and "field" in problem["properties"]
    assert "HTTPValidationError" not in spec["components"]["schemas"]  # FastAPI's 422 replaced
    n = 0
    for method, path, op in operations(spec):
        codes = {int(c) for c in op["responses"] if c.isdigit()}
        assert 500 in codes, (method, path)
        if op.get("security"):
            assert 401 in codes, (method, path)
        for code, resp in op["responses"].items():
            if int(code) >= 400:
                assert resp["content"] == {PROBLEM: {"schema": {"$ref": "#/components/schemas/Problem"}}}, \
                    (method, path, code)
                assert resp["description"]
                n += 1
    assert n >= 50


def test_request_body_examples_are_valid_requests(spec: dict[str, Any]) -> None:
    schemas = spec["components"]["schemas"]
    for name, model in (("MissionRequest", MissionRequest), ("SinRequest", SinRequest),
                        ("DesignRequest", DesignRequest), ("BatchCreate", BatchCreate)):
        examples = schemas[name]["examples"]
        assert examples, name
        for ex in examples:
            model.model_validate(ex)


def test_unexpected_exception_is_problem_json_500_with_request_id(app: Any) -> None:
    local = create_app(Settings())

    @local.get("/boom", include_in_schema=False)
    async def boom() -> None:
        raise RuntimeError("a bug")

    client = InProcess(local)
    r = client.get("/boom", headers={"X-Request-ID": "abc-123"})
    assert r.status_code == 500 and r.headers["content-type"].startswith(PROBLEM)
    body = r.json()
    assert body["status"] == 500 and body["request_id"] == "abc-123" and "a bug" not in r.text
    assert r.headers["x-request-id"] == "abc-123"


def test_request_ids_are_kept_or_made(app: Any) -> None:
    client = InProcess(app)
    assert client.get("/healthz", headers={"X-Request-ID": "job-7.a:b"}).headers["x-request-id"] == "job-7.a:b"
    made = client.get("/healthz").headers["x-request-id"]
    assert re.fullmatch(r"[0-9a-f]{32}", made)
    bad = client.get("/healthz", headers={"X-Request-ID": "no spaces\tor tabs"}).headers["x-request-id"]
    assert re.fullmatch(r"[0-9a-f]{32}", bad)  # an unsafe id is replaced, never echoed into logs
    assert client.get("/healthz").headers["x-request-id"] != made
