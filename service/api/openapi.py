"""The OpenAPI document as generated clients expect it, at app level (no route body changes).

* ``operation_id``: FastAPI's ``generate_unique_id_function``: readable operationIds
  (``optimize_reference``, ``get_batch``, ...) instead of ``optimize_v1_references_optimize_post``;
  a route missing from :data:`OPERATION_IDS` keeps its function name.
* :func:`install`: every error response (4xx/5xx, including FastAPI's own 422) is documented as
  ``application/problem+json`` with the :class:`~service.schemas.Problem` schema; every operation
  documents the 500 an unexpected failure answers, and 401 where the API key applies.
"""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI
from fastapi.openapi.utils import get_openapi
from fastapi.routing import APIRoute

from service.api.problems import _TITLES, PROBLEM

#: route function name -> operationId (verb + object: the method name in a generated client)
OPERATION_IDS: dict[str, str] = {
    "healthz": "health", "info": "get_info", "analytic": "analytic_reference", "optimize": "optimize_reference",
    "compare": "compare_shapes", "submit": "submit_batch", "status": "get_batch", "results": "get_batch_results",
    "check": "check_model", "diagnose": "diagnose_model", "fit": "fit_model",
}

_REF = {"$ref": "#/components/schemas/Problem"}
_FASTAPI_422 = ("HTTPValidationError", "ValidationError")


def operation_id(route: APIRoute) -> str:
    """``generate_unique_id_function``: the operationId of ``route``."""
    return OPERATION_IDS.get(route.name, route.name)


def _problem_schema() -> dict[str, Any]:
    from service.schemas import Problem

    return Problem.model_json_schema(ref_template="#/components/schemas/{model}")


def _errors(op: dict[str, Any]) -> None:
    """Problem+json on every error response of one operation; 500 always, 401 behind the API key."""
    responses: dict[str, Any] = op.setdefault("responses", {})
    if op.get("security"):
        responses.setdefault("401", {})
    responses.setdefault("500", {})
    for code, resp in responses.items():
        if code.isdigit() and int(code) >= 400:
            resp["content"] = {PROBLEM: {"schema": _REF}}
            resp.setdefault("description", _TITLES.get(int(code), "Error"))
            if resp["description"] in ("Validation Error", "Error"):  # FastAPI's and our defaults
                resp["description"] = _TITLES.get(int(code), "Error")
    if "500" in responses:
        responses["500"]["description"] = "Unexpected server error (problem+json)"


def _unused(schema: dict[str, Any], name: str) -> bool:
    import json

    return f'"#/components/schemas/{name}"' not in json.dumps(schema)


def build(app: FastAPI) -> dict[str, Any]:
    """The app's OpenAPI document with the conventions above (cached on ``app.openapi_schema``)."""
    if app.openapi_schema is not None:
        return app.openapi_schema
    schema = get_openapi(title=app.title, version=app.version, summary=app.summary, description=app.description,
                         routes=app.routes, servers=app.servers)
    for path in schema.get("paths", {}).values():
        for op in path.values():
            if isinstance(op, dict) and "responses" in op:
                _errors(op)
    schemas = schema.setdefault("components", {}).setdefault("schemas", {})
    schemas["Problem"] = _problem_schema()
    for name in _FASTAPI_422:
        if name in schemas and _unused(schema, name):
            del schemas[name]
    app.openapi_schema = schema
    return schema


def install(app: FastAPI) -> None:
    """Make ``app.openapi()`` answer :func:`build`."""
    app.openapi = lambda: build(app)  # type: ignore[method-assign]
