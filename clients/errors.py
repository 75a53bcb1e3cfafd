"""Errors of the thrustshape HTTP client, a tree so callers catch as broadly or as narrowly as they need::

    ClientError                      root: everything this module raises
    ├── TransportError               no HTTP answer (connection refused, reset, ...)
    │   └── Timeout                  no answer within the client's timeout
    └── APIError                     the server answered with an error (problem+json parsed)
        ├── MalformedResponse        the answer breaks the protocol (e.g. an unreadable Retry-After)
        ├── BadRequest(ValueError)   4xx: .field and .reason say what to fix
        │   ├── Unauthorized         401: missing or wrong API key
        │   ├── NotFound             404
        │   ├── PayloadTooLarge      413
        │   └── InvalidInput         422
        ├── ServerBusy               503 after the retries
        └── ServerError              other 5xx (504: ComputationTimeout)
            └── ComputationTimeout
"""

from __future__ import annotations

import email.utils
import math
import time
from collections.abc import Mapping
from typing import Any

import httpx


class ClientError(Exception):
    """Root of the client's errors."""


class TransportError(ClientError):
    """The request got no HTTP answer."""


class Timeout(TransportError):
    """No answer within the client's timeout."""


class APIError(ClientError):
    """The server answered with an error status; fields of its problem+json body are attributes."""

    def __init__(self, status: int, problem: Mapping[str, Any], headers: Mapping[str, str] | None = None) -> None:
        self.status = status
        self.problem = dict(problem)
        self.title = str(problem.get("title", ""))
        self.detail = str(problem.get("detail", ""))
        self.field: str | None = problem.get("field")
        self.reason: str | None = problem.get("reason")
        self.headers = dict(headers or {})
        super().__init__(f"{status} {self.title}: {self.detail}".strip())


class MalformedResponse(APIError):
    """The server's answer cannot be read as the protocol says (e.g. a ``Retry-After`` that is neither
    seconds nor an HTTP date); ``field`` names the header."""


class BadRequest(APIError, ValueError):
    """4xx: the request must change before it can succeed."""


class Unauthorized(BadRequest):
    """401: missing or wrong API key."""


class NotFound(BadRequest):
    """404."""


class PayloadTooLarge(BadRequest):
    """413: a body, batch or profile over the server's limits."""


class InvalidInput(BadRequest):
    """422: ``field`` names the offending input, ``reason`` what is wrong with it."""


class ServerBusy(APIError):
    """503 still after the retries; ``retry_after`` [s] from the last answer."""

    @property
    def retry_after(self) -> float | None:
        """Seconds the server asked to wait, or None (absent or unreadable)."""
        try:
            return _retry_after(self.headers.get("retry-after"))
        except ValueError:
            return None


class ServerError(APIError):
    """5xx other than 503."""


class ComputationTimeout(ServerError):
    """504: the computation hit the server's hard timeout."""


_BY_STATUS: dict[int, type[APIError]] = {401: Unauthorized, 404: NotFound, 413: PayloadTooLarge, 422: InvalidInput,
                                         503: ServerBusy, 504: ComputationTimeout}


def _retry_after(value: str | None) -> float | None:
    """Seconds from a ``Retry-After`` value (delay-seconds or an HTTP date); ValueError when it is neither."""
    if value is None:
        return None
    try:
        seconds = float(value)
    except ValueError:
        try:
            when = email.utils.parsedate_to_datetime(value)
        except (TypeError, ValueError, IndexError, OverflowError):
            raise ValueError(f"Retry-After {value!r} is neither seconds nor an HTTP date") from None
        return max(when.timestamp() - time.time(), 0.0)
    if not math.isfinite(seconds):
        raise ValueError(f"Retry-After {value!r} is not a finite number of seconds")
    return max(seconds, 0.0)


def _error(resp: httpx.Response) -> APIError:
    try:
        body = resp.json()
    except ValueError:
        body = None
    if not isinstance(body, dict):
        body = {"title": resp.reason_phrase, "detail": resp.text[:500]}
    cls = _BY_STATUS.get(resp.status_code) or (BadRequest if resp.status_code < 500 else ServerError)
    return cls(resp.status_code, body, {k.lower(): v for k, v in resp.headers.items()})
