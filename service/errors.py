"""The service's own errors: one base that carries the HTTP answer, mapped once to problem+json.

::

    ServiceError                      root: ``status`` and ``title`` of the answer, optional field/reason
    ├── TooLarge                 413  a request within the body limit asks for more than a configured cap
    │   └── BodyTooLarge         413  the body is over ``max_body_bytes`` (service.api.problems; an HTTPException too)
    ├── IdempotencyConflict      422  an Idempotency-Key reused with a different body
    ├── FeatureUnavailable       501  the route's core backend is not installed on this server
    ├── TaskFailed               500  a task raised an unexpected exception or its worker process died
    ├── QueueFull                503  every worker busy and the wait queue full (+ Retry-After)
    ├── StoreUnavailable         503  the job store cannot be used right now (+ Retry-After)
    └── TaskTimeout              504  a task ran out of time (waiting, starting, building or computing)
        └── DeadlineExceeded     504  neither the solver nor the fallback answered within the deadline

Errors about the user's *input* are the core's :class:`ocp.errors.ThrustshapeError` tree (422, naming the
field); this tree is about the service: capacity, time, storage, what is installed. Both are mapped in
:mod:`service.api.problems`, this one by a single handler that reads ``status``, ``title``, ``http_headers()``
and ``extra()`` from the exception. Nothing here imports FastAPI: the worker pool and the job store raise
these without depending on the web layer.
"""

from __future__ import annotations

from typing import Any, ClassVar


class ServiceError(Exception):
    """Root of the service's own errors; subclasses set the answer's ``status`` and ``title``.

    ``field`` and ``reason`` name the input at fault when there is one (a header, a request field).
    """

    status: ClassVar[int] = 500
    title: ClassVar[str] = "Service error"

    def __init__(self, detail: str, field: str | None = None, reason: str | None = None) -> None:
        self.field, self.reason = field, reason
        super().__init__(detail)

    def http_headers(self) -> dict[str, str] | None:
        """Extra response headers (e.g. ``Retry-After``)."""
        return None

    def extra(self) -> dict[str, Any]:
        """Extra members of the problem+json body."""
        return {}


class TooLarge(ServiceError):
    """A request within the body limit asks for more than a configured cap (413)."""

    status, title = 413, "Request too large"

    def __init__(self, field: str, reason: str) -> None:
        super().__init__(f"{field}: {reason}", field, reason)


class IdempotencyConflict(ServiceError):
    """The idempotency key is already bound to a batch with a different body (422, as the IETF
    Idempotency-Key draft answers a key reused for another payload)."""

    status, title = 422, "Idempotency key reused"

    def __init__(self, key: str, batch_id: str) -> None:
        self.key, self.batch_id = key, batch_id
        super().__init__(f"idempotency key {key!r} was used for batch {batch_id} with a different body",
                         "Idempotency-Key", "already used for a different request body")

    def extra(self) -> dict[str, Any]:
        return {"batch_id": self.batch_id}


class FeatureUnavailable(ServiceError):
    """The route exists in the API but its core backend is not installed here (501 Not Implemented: the
    server does not support the functionality; a retry will not help, ``GET /v1/info`` lists what exists).
    Routes whose backend is missing are not registered at all (404); this guards a call that gets past that."""

    status, title = 501, "Not available on this server"

    def __init__(self, feature: str, backend: str) -> None:
        super().__init__(f"{feature} is not available on this server: {backend} is not installed",
                         "route", f"{backend} is not installed on this server")


class TaskFailed(ServiceError):
    """A task raised an unexpected exception or its process died; ``detail`` says what happened;
    ``startup``: the process died before the task reached it (the task is not to blame)."""

    status, title = 500, "Computation failed"

    def __init__(self, detail: str, startup: bool = False) -> None:
        self.detail, self.startup = detail, startup
        super().__init__(detail)


class QueueFull(ServiceError):
    """Every worker is busy and the wait queue is full; retry after ``retry_after`` seconds."""

    status, title = 503, "Server busy"

    def __init__(self, retry_after: int) -> None:
        self.retry_after = retry_after
        super().__init__(f"all workers busy and queue full; retry after {retry_after} s")

    def http_headers(self) -> dict[str, str] | None:
        return {"Retry-After": str(self.retry_after)}


class StoreUnavailable(ServiceError):
    """The job store cannot be used right now (file vanished, disk error, locked past the busy timeout)."""

    status, title = 503, "Store unavailable"
    retry_after = 5

    def http_headers(self) -> dict[str, str] | None:
        return {"Retry-After": str(self.retry_after)}


class TaskTimeout(ServiceError):
    """A task ran out of time; ``phase`` says where: waiting for a free worker (``queue``), waiting for a
    new worker process to start (``start-up``, e.g. after a respawn), building its solver (``build``) or
    computing (``run``: its process was killed, or on Dask the task abandoned)."""

    status, title = 504, "Computation timed out"
    #: what a task was waiting for when its deadline ran out
    PHASES: ClassVar[dict[str, str]] = {"queue": "waiting for a free worker",
                                        "start-up": "waiting for a worker process to start",
                                        "build": "building the solver", "run": "computing"}

    def __init__(self, timeout: float, phase: str = "run") -> None:
        self.timeout, self.phase = timeout, phase
        super().__init__(f"the {timeout:.3g} s deadline ran out while {self.PHASES[phase]} ({phase})")


class DeadlineExceeded(TaskTimeout):
    """Neither the solver nor the fallback answered within the request's deadline (504); ``detail`` says
    which part ran out of time where."""

    def __init__(self, total: float, detail: str) -> None:
        super().__init__(total)
        self.args = (f"the {total:.3g} s deadline ran out: {detail}",)
