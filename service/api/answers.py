"""Large JSON answers (references of thousands of samples) checked against their model and rendered in one step.

FastAPI would validate a route's answer against its ``response_model``, dump it to Python objects and render
those with the standard library's ``json``: for an optimised reference (about 16,000 numbers, 200 kB) that is
tens of milliseconds of the server's single event loop per request. :func:`json_answer` checks the answer's
documented fields with the same model (extra fields pass through untouched) and renders the worker's JSON-safe
dict with ``pydantic_core.to_json`` (Rust). The route keeps its ``response_model``, so OpenAPI documents the
answer exactly as before.
"""

from __future__ import annotations

from typing import Any

import pydantic_core
from fastapi.responses import Response
from pydantic import BaseModel


def json_answer(model: type[BaseModel], data: dict[str, Any]) -> Response:
    """``data`` (JSON-safe: non-finite numbers already spelled as strings by the core) as an
    ``application/json`` answer, after checking it against ``model`` (raises on a malformed answer, which the
    server reports as a 500)."""
    model.model_validate(data)
    return Response(pydantic_core.to_json(data), media_type="application/json")
