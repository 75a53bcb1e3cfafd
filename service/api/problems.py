"""One place that turns every error into ``application/problem+json`` (RFC 9457) naming field and reason.

Four trees, one handler each: request validation (422), the core's :class:`~ocp.errors.ThrustshapeError`
(422, naming the field), the service's own :class:`~service.errors.ServiceError` (its ``status`` and
``title``), and Starlette's HTTP errors (404, 405, ...)."""

from __future__ import annotations

from typing import Any

from fastapi import FastAPI, Request
from fastapi.exceptions import RequestValidationError
from fastapi.responses import JSONResponse
from starlette.exceptions import HTTPException

from ocp.errors import SEGMENT_TAGS, InfeasibleError, SolverError, ThrustshapeError, validation_location
from service.errors import ServiceError, TooLarge

PROBLEM = "application/problem+json"


def error_responses(*codes: int) -> dict[int | str, dict[str, Any]]:
    """OpenAPI ``responses`` entries documenting problem+json answers."""
    from service.schemas import Problem

    return {code: {"model": Problem, "content": {PROBLEM: {}}, "description": _TITLES.get(code, "Error")}
            for code in codes}


def problem(status: int, title: str, detail: str, field: str | None = None, reason: str | None = None,
            headers: dict[str, str] | None = None, **extra: Any) -> JSONResponse:
    body: dict[str, Any] = {"type": "about:blank", "title": title, "status": status, "detail": detail}
    if field is not None:
        body["field"] = field
    if reason is not None:
        body["reason"] = reason
    body.update(extra)
    return JSONResponse(body, status_code=status, media_type=PROBLEM, headers=headers)


class BodyTooLarge(TooLarge, HTTPException):
    """Request body over ``max_body_bytes`` (413; also an HTTPException so FastAPI's body parsing passes it
    through instead of answering 400)."""

    def __init__(self, limit: int, field: str = "body") -> None:
        reason = f"request body larger than {limit} bytes"
        TooLarge.__init__(self, field, reason)
        HTTPException.__init__(self, 413, reason)
        self.args = (reason,)


#: union tags of the request models (analytic sin/design requests, mission segments)
_TAGS = SEGMENT_TAGS | {"sin", "design"}


def _field(err: dict[str, Any]) -> tuple[str, str]:
    if err.get("type") == "json_invalid":
        return "body", f"invalid JSON: {str(err.get('msg', 'invalid')).removeprefix('Value error, ')}"
    loc = tuple(err.get("loc", ()))
    if loc and loc[0] in ("body", "query", "path", "header"):
        loc = loc[1:]
    field, reason = validation_location({**err, "loc": loc}, _TAGS)
    return field or "body", reason


async def _validation(request: Request, exc: Exception) -> JSONResponse:
    if not isinstance(exc, RequestValidationError):
        raise exc
    errs = [_field(e) for e in exc.errors()]
    field, reason = errs[0] if errs else ("body", "invalid request")
    return problem(422, "Invalid request", f"{field}: {reason}", field, reason,
                   errors=[{"field": f, "reason": r} for f, r in errs])


async def _core(request: Request, exc: Exception) -> JSONResponse:
    if not isinstance(exc, ThrustshapeError):
        raise exc
    title = ("Solver failed" if isinstance(exc, SolverError) else
             "Infeasible within the limits" if isinstance(exc, InfeasibleError) else "Invalid input")
    form = getattr(exc, "form_field", None)  # model-check uploads: the form input the field belongs to
    extra: dict[str, Any] = {"form_field": form} if isinstance(form, str) else {}
    if isinstance(exc, InfeasibleError):
        extra["code"] = "infeasible"
    return problem(422, title, str(exc), exc.field, exc.reason, error_type=type(exc).__name__, **extra)


async def _http(request: Request, exc: Exception) -> JSONResponse:
    if not isinstance(exc, HTTPException):
        raise exc
    headers = dict(exc.headers or {})
    return problem(exc.status_code, _TITLES.get(exc.status_code, "Error"), str(exc.detail), headers=headers or None)


async def _service(request: Request, exc: Exception) -> JSONResponse:
    """The one handler of the service's own errors (:mod:`service.errors`): each carries its answer."""
    if not isinstance(exc, ServiceError):
        raise exc
    return problem(exc.status, exc.title, str(exc), exc.field, exc.reason, headers=exc.http_headers(),
                   error_type=type(exc).__name__, **exc.extra())


_TITLES = {400: "Bad request", 401: "Unauthorized", 403: "Forbidden", 404: "Not found", 405: "Method not allowed",
           406: "Not acceptable", 413: "Request too large", 415: "Unsupported media type", 422: "Invalid input",
           500: "Computation failed", 501: "Not available on this server", 503: "Server busy",
           504: "Computation timed out"}


def install(app: FastAPI) -> None:
    """Register every handler on ``app``."""
    app.add_exception_handler(RequestValidationError, _validation)
    app.add_exception_handler(ThrustshapeError, _core)
    app.add_exception_handler(HTTPException, _http)
    app.add_exception_handler(ServiceError, _service)
