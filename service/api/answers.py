"""Large JSON answers (references of thousands of samples) checked against their model and rendered in one step.

FastAPI would validate a route's answer against its ``response_model``, dump it to Python objects and render
those with the standard library's ``json``: for an optimised reference (about 16,000 numbers, 200 kB) that is
tens of milliseconds of the server's single event loop per request. The optimise route's tasks check and render
their answer in the worker (:func:`service.tasks.optimize_answer`), so the server only sends the bytes; an answer
that comes as a dict (another task set's) :func:`json_answer` checks the
documented fields with the same model (extra fields pass through untouched) and renders the worker's JSON-safe
dict with ``pydantic_core.to_json`` (Rust). The route keeps its ``response_model``, so OpenAPI documents the
answer exactly as before.
"""

from __future__ import annotations

from typing import Any

import pydantic_core
from fastapi.responses import Response
from pydantic import BaseModel

from service.tasks import RENDERED


def json_answer(model: type[BaseModel], data: dict[str, Any]) -> Response:
    """``data`` (JSON-safe: non-finite numbers already spelled as strings by the core) as an
    ``application/json`` answer, after checking it against ``model`` (raises on a malformed answer, which the
    server reports as a 500). An answer the worker already checked and rendered (``{RENDERED: bytes}``,
    :func:`service.tasks.optimize_answer`) is sent as it is."""
    if set(data) == {RENDERED} and isinstance(data[RENDERED], bytes):
        return Response(data[RENDERED], media_type="application/json")
    model.model_validate(data)
    return Response(pydantic_core.to_json(data), media_type="application/json")
