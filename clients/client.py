"""HTTP client of the thrustshape service: :class:`Client` (sync) and :class:`AsyncClient`, on httpx.

Both wrap an ``httpx`` client; pass ``transport=`` to talk to an app in-process (e.g.
``httpx.ASGITransport(app)``) or through any other httpx transport. A 503 is retried up to
``retries`` times, waiting what the server's ``Retry-After`` says (capped by ``max_retry_wait``);
``wait_batch`` polls through dropped connections (``reconnects`` in a row, with backoff).
Errors form a tree, so callers catch as broadly or as narrowly as they need::

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

import asyncio
import contextlib
import email.utils
import json
import math
import os
import time
from collections.abc import Callable, Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import httpx
from pydantic import BaseModel

DEFAULT_TIMEOUT = httpx.Timeout(60.0, connect=5.0)


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


def _json(obj: BaseModel | Mapping[str, Any]) -> dict[str, Any]:
    return obj.model_dump(mode="json") if isinstance(obj, BaseModel) else dict(obj)


#: a log to upload: a local file path, or ``(file name, bytes)``
LogSource = str | os.PathLike[str] | tuple[str, bytes]
Form = tuple[dict[str, tuple[str, bytes]], dict[str, str]]
#: read options of a model-check upload (:class:`ocp.logs.ReadOptions` fields, e.g. ``{"pole_pairs": 7}``)
ReadFields = Mapping[str, Any] | None


def model_check_form(log: LogSource, params: str | Mapping[str, Any], *, columns: Mapping[str, Any] | None = None,
                     steady_state: bool | None = None, read: ReadFields = None, **fields: Any) -> Form:
    """``(files, data)`` of a ``/v1/model-check/*`` upload.

    ``params`` is a preset name, the JSON text of a parameter mapping, or the mapping itself (never a
    path: read a local parameter file yourself and pass its mapping). ``fields`` are the extra form
    fields (``effects`` as a comma-separated string or a list of names; ``max_effects``, ``corrections``,
    ``refine``; the read options ``pole_pairs``, ``neutral_us``, ``throttle_range_us``, ``electrical``, ``motor``,
    ``resample`` of :class:`ocp.logs.ReadOptions`); ``None`` values are left out. ``steady_state=None``: the
    server detects a sweep where the file makes it plain.
    """
    if isinstance(log, tuple):
        name, data = log
    else:
        path = Path(log)
        name, data = path.name, path.read_bytes()
    form = {"params": params if isinstance(params, str) else json.dumps(dict(params), allow_nan=False)}
    if steady_state is not None:
        form["steady_state"] = "true" if steady_state else "false"
    if columns is not None:
        form["columns"] = json.dumps(dict(columns))
    for key, value in fields.items():
        if value is None:
            continue
        if isinstance(value, bool):
            form[key] = "true" if value else "false"
        elif isinstance(value, list | tuple):
            form[key] = ",".join(str(v) for v in value)
        else:
            form[key] = str(value)
    return {"log": (name, data)}, form


def _qs(qs: Iterable[int] | None) -> dict[str, list[int]] | None:
    return None if qs is None else {"qs": [int(q) for q in qs]}


class _Spec:
    """What both clients share: request building, answer parsing, the retry policy."""

    def __init__(self, base_url: str, api_key: str | None, retries: int, max_retry_wait: float) -> None:
        if retries < 0:
            raise ValueError("retries must be >= 0")
        self.base_url = base_url.rstrip("/")
        self.headers = {"Accept": "application/json"}
        if api_key:
            self.headers["Authorization"] = f"Bearer {api_key}"
        self.retries, self.max_retry_wait = retries, max_retry_wait

    @staticmethod
    @contextlib.contextmanager
    def transport_errors(method: str, path: str) -> Iterator[None]:
        """httpx's timeout and transport failures as this client's :class:`Timeout` / :class:`TransportError`."""
        try:
            yield
        except httpx.TimeoutException as exc:
            raise Timeout(f"{method} {path}: {exc}") from exc
        except httpx.TransportError as exc:
            raise TransportError(f"{method} {path}: {exc}") from exc

    def wait(self, resp: httpx.Response, attempt: int) -> float | None:
        """Seconds to wait before retrying ``resp``, or None when it is final."""
        if resp.status_code != 503 or attempt >= self.retries:
            return None
        try:
            after = _retry_after(resp.headers.get("retry-after"))
        except ValueError as exc:
            problem = {"title": "Malformed Retry-After", "detail": str(exc), "field": "Retry-After",
                       "reason": "neither seconds nor an HTTP date"}
            raise MalformedResponse(resp.status_code, problem, dict(resp.headers)) from None
        return min(after if after is not None else 0.5 * 2**attempt, self.max_retry_wait)

    @staticmethod
    def reconnect_delay(failures: int, backoff: float) -> float:
        """Wait before the next poll after ``failures`` dropped connections in a row [s]."""
        return min(backoff * 2 ** (failures - 1), 10.0)

    @staticmethod
    def result(resp: httpx.Response) -> httpx.Response:
        if resp.status_code >= 400:
            raise _error(resp)
        return resp


class Client:
    """Synchronous client; use as a context manager or call :meth:`close`.

    Args:
        base_url: e.g. ``http://127.0.0.1:8000``.
        api_key: bearer token when the server requires one.
        timeout: seconds (or an ``httpx.Timeout``) per HTTP request.
        retries: extra attempts after a 503; waits honour ``Retry-After``.
        transport: any httpx transport (tests: the app in-process).
    """

    def __init__(self, base_url: str = "http://127.0.0.1:8000", *, api_key: str | None = None,
                 timeout: float | httpx.Timeout = DEFAULT_TIMEOUT, retries: int = 3, max_retry_wait: float = 30.0,
                 transport: httpx.BaseTransport | None = None) -> None:
        self._spec = _Spec(base_url, api_key, retries, max_retry_wait)
        self._http = httpx.Client(base_url=self._spec.base_url, headers=self._spec.headers, timeout=timeout,
                                  transport=transport)

    def __enter__(self) -> Client:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def close(self) -> None:
        self._http.close()

    def _request(self, method: str, path: str, **kw: Any) -> httpx.Response:
        attempt = 0
        while True:
            with self._spec.transport_errors(method, path):
                resp = self._http.request(method, path, **kw)
            delay = self._spec.wait(resp, attempt)
            if delay is None:
                return self._spec.result(resp)
            time.sleep(delay)
            attempt += 1

    def health(self) -> dict[str, Any]:
        return self._request("GET", "/healthz").json()

    def info(self) -> dict[str, Any]:
        return self._request("GET", "/v1/info").json()

    def analytic(self, request: Mapping[str, Any]) -> dict[str, Any]:
        """``{"amplitude", "period", "q", ...}`` or a design request ``{"amplitude" | "period", "limits", ...}``."""
        return self._request("POST", "/v1/references/analytic", json=dict(request)).json()

    def optimize(self, mission: BaseModel | Mapping[str, Any]) -> dict[str, Any]:
        return self._request("POST", "/v1/references/optimize", json=_json(mission)).json()

    def compare(self, mission: BaseModel | Mapping[str, Any], qs: Iterable[int] | None = None) -> dict[str, Any]:
        """Analytic ``A sin^(2q+1)`` shapes (``qs``, default 0-3) vs the optimised reference."""
        return self._request("POST", "/v1/compare", json=_json(mission), params=_qs(qs)).json()

    def check(self, log: LogSource, params: str | Mapping[str, Any], *, columns: Mapping[str, Any] | None = None,
              steady_state: bool | None = None, read: ReadFields = None) -> dict[str, Any]:
        """Model check: where the model fails on ``log`` (see :func:`model_check_form` for the arguments)."""
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}))
        return self._request("POST", "/v1/model-check/check", files=files, data=data).json()

    def check_report(self, log: LogSource, params: str | Mapping[str, Any], *,
                     columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                     read: ReadFields = None) -> str:
        """The self-contained HTML report of :meth:`check`."""
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}))
        return self._request("POST", "/v1/model-check/check", files=files, data=data,
                             params={"report": "html"}).text

    def diagnose(self, log: LogSource, params: str | Mapping[str, Any], *, columns: Mapping[str, Any] | None = None,
                 steady_state: bool | None = None, read: ReadFields = None, max_effects: int | None = None,
                 corrections: bool | None = None, tolerance: float | None = None,
                 max_logging_skew: float | None = None) -> dict[str, Any]:
        """Which catalogue effects are missing (``verdict``), candidates ranked by held-out error (synchronous:
        bounded by the server's task timeout; :meth:`submit_model_check` runs it as a job)."""
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       max_effects=max_effects, corrections=corrections, tolerance=tolerance,
                                       max_logging_skew=max_logging_skew)
        return self._request("POST", "/v1/model-check/diagnose", files=files, data=data).json()

    def submit_model_check(self, op: str, log: LogSource, params: str | Mapping[str, Any], *,
                           columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                           read: ReadFields = None, **fields: Any) -> dict[str, Any]:
        """Submit a model check as a job (``op``: check, diagnose, fit, design); returns ``{"id", "status",
        "progress", ...}``. ``fields``: the op's form fields (``max_effects``, ``corrections``, ``tolerance``,
        ``max_logging_skew``, ``effects``, ``refine``, ``voltage``, ``current``, ``duration_s``, ``rivals``:
        a list of lists of items or the text ``"a;b,c"``)."""
        rivals = fields.get("rivals")
        if rivals is not None and not isinstance(rivals, str):
            fields["rivals"] = ";".join(",".join(r) for r in rivals)
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       op=op, **fields)
        return self._request("POST", "/v1/model-check/jobs", files=files, data=data).json()

    def model_check_job(self, job_id: str) -> dict[str, Any]:
        """A model-check job's ``status`` and ``progress``."""
        return self._request("GET", f"/v1/model-check/jobs/{job_id}").json()

    def model_check_result(self, job_id: str) -> dict[str, Any]:
        """A finished job's result; a failed job raises its problem (e.g. :class:`InvalidInput` naming the field)."""
        return self._request("GET", f"/v1/model-check/jobs/{job_id}/result").json()

    def wait_model_check(self, job_id: str, *, poll: float = 0.3, timeout: float | None = None,
                         on_progress: Callable[[float], None] | None = None, reconnects: int = 5,
                         backoff: float = 0.5) -> dict[str, Any]:
        """Poll a job until it finished (``on_progress(fraction)`` each time), then return its result (or raise
        its problem). Dropped connections are retried like :meth:`wait_batch`'s; raises :class:`Timeout`."""
        end = None if timeout is None else time.monotonic() + timeout
        failures = 0
        while True:
            try:
                status = self.model_check_job(job_id)
            except TransportError:
                failures += 1
                if failures > reconnects or (end is not None and time.monotonic() > end):
                    raise
                time.sleep(self._spec.reconnect_delay(failures, backoff))
                continue
            failures = 0
            if on_progress is not None:
                on_progress(1.0 if status["status"] == "done" else float(status["progress"]))
            if status["status"] in ("done", "failed"):
                return self.model_check_result(job_id)
            if end is not None and time.monotonic() > end:
                raise Timeout(f"model-check job {job_id} not finished after {timeout} s")
            time.sleep(poll)

    def design_experiment(self, log: LogSource, params: str | Mapping[str, Any], *,
                          on_progress: Callable[[float], None] | None = None, timeout: float | None = None,
                          **fields: Any) -> dict[str, Any]:
        """Diagnose ``log`` and design the experiment that settles it (a job; see :meth:`submit_model_check` for
        ``fields``); returns the design with its ``mission`` and its ``diagnosis``."""
        job = self.submit_model_check("design", log, params, **fields)
        return self.wait_model_check(job["id"], timeout=timeout, on_progress=on_progress)

    def fit(self, log: LogSource, params: str | Mapping[str, Any], effects: str | Iterable[str], *,
            columns: Mapping[str, Any] | None = None, steady_state: bool | None = None, read: ReadFields = None,
            refine: bool | None = None) -> dict[str, Any]:
        """Add ``effects`` and refit; the answer's ``calibrated_params`` is the calibrated parameter mapping."""
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       effects=effects if isinstance(effects, str) else list(effects), refine=refine)
        return self._request("POST", "/v1/model-check/fit", files=files, data=data).json()

    def submit_batch(self, missions: Iterable[BaseModel | Mapping[str, Any]],
                     idempotency_key: str | None = None) -> dict[str, Any]:
        """Submit missions; returns ``{"id", "status"}``. With a key, resubmitting returns the same batch."""
        headers = {"Idempotency-Key": idempotency_key} if idempotency_key else None
        body = {"missions": [_json(m) for m in missions]}
        return self._request("POST", "/v1/batches", json=body, headers=headers).json()

    def batch(self, batch_id: str) -> dict[str, Any]:
        return self._request("GET", f"/v1/batches/{batch_id}").json()

    def batch_results(self, batch_id: str) -> dict[str, Any]:
        return self._request("GET", f"/v1/batches/{batch_id}/results").json()

    def batch_results_csv(self, batch_id: str) -> str:
        return self._request("GET", f"/v1/batches/{batch_id}/results", params={"format": "csv"}).text

    def wait_batch(self, batch_id: str, *, poll: float = 0.5, timeout: float | None = None,
                   on_progress: Callable[[dict[str, Any]], None] | None = None, reconnects: int = 5,
                   backoff: float = 0.5) -> dict[str, Any]:
        """Poll until the batch is done or failed; returns its last status. Raises :class:`Timeout`.

        A dropped connection (e.g. the server restarting) is retried up to ``reconnects`` times in a row,
        waiting ``backoff`` [s], doubled each time (at most 10 s); the batch is stored, so nothing is lost.
        """
        end = None if timeout is None else time.monotonic() + timeout
        failures = 0
        while True:
            try:
                status = self.batch(batch_id)
            except TransportError:
                failures += 1
                if failures > reconnects or (end is not None and time.monotonic() > end):
                    raise
                time.sleep(self._spec.reconnect_delay(failures, backoff))
                continue
            failures = 0
            if on_progress is not None:
                on_progress(status)
            if status["status"] in ("done", "failed"):
                return status
            if end is not None and time.monotonic() > end:
                raise Timeout(f"batch {batch_id} not finished after {timeout} s")
            time.sleep(poll)


class AsyncClient:
    """Asynchronous twin of :class:`Client` (same arguments, ``await`` every call, ``async with``)."""

    def __init__(self, base_url: str = "http://127.0.0.1:8000", *, api_key: str | None = None,
                 timeout: float | httpx.Timeout = DEFAULT_TIMEOUT, retries: int = 3, max_retry_wait: float = 30.0,
                 transport: httpx.AsyncBaseTransport | None = None) -> None:
        self._spec = _Spec(base_url, api_key, retries, max_retry_wait)
        self._http = httpx.AsyncClient(base_url=self._spec.base_url, headers=self._spec.headers, timeout=timeout,
                                       transport=transport)

    async def __aenter__(self) -> AsyncClient:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.aclose()

    async def aclose(self) -> None:
        await self._http.aclose()

    async def _request(self, method: str, path: str, **kw: Any) -> httpx.Response:
        attempt = 0
        while True:
            with self._spec.transport_errors(method, path):
                resp = await self._http.request(method, path, **kw)
            delay = self._spec.wait(resp, attempt)
            if delay is None:
                return self._spec.result(resp)
            await asyncio.sleep(delay)
            attempt += 1

    async def _json(self, method: str, path: str, **kw: Any) -> dict[str, Any]:
        return (await self._request(method, path, **kw)).json()

    async def health(self) -> dict[str, Any]:
        return await self._json("GET", "/healthz")

    async def info(self) -> dict[str, Any]:
        return await self._json("GET", "/v1/info")

    async def analytic(self, request: Mapping[str, Any]) -> dict[str, Any]:
        return await self._json("POST", "/v1/references/analytic", json=dict(request))

    async def optimize(self, mission: BaseModel | Mapping[str, Any]) -> dict[str, Any]:
        return await self._json("POST", "/v1/references/optimize", json=_json(mission))

    async def compare(self, mission: BaseModel | Mapping[str, Any], qs: Iterable[int] | None = None) -> dict[str, Any]:
        return await self._json("POST", "/v1/compare", json=_json(mission), params=_qs(qs))

    async def check(self, log: LogSource, params: str | Mapping[str, Any], *,
                    columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                    read: ReadFields = None) -> dict[str, Any]:
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}))
        return await self._json("POST", "/v1/model-check/check", files=files, data=data)

    async def check_report(self, log: LogSource, params: str | Mapping[str, Any], *,
                           columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                           read: ReadFields = None) -> str:
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}))
        return (await self._request("POST", "/v1/model-check/check", files=files, data=data,
                                    params={"report": "html"})).text

    async def diagnose(self, log: LogSource, params: str | Mapping[str, Any], *,
                       columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                       read: ReadFields = None, max_effects: int | None = None, corrections: bool | None = None,
                       tolerance: float | None = None, max_logging_skew: float | None = None) -> dict[str, Any]:
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       max_effects=max_effects, corrections=corrections, tolerance=tolerance,
                                       max_logging_skew=max_logging_skew)
        return await self._json("POST", "/v1/model-check/diagnose", files=files, data=data)

    async def submit_model_check(self, op: str, log: LogSource, params: str | Mapping[str, Any], *,
                                 columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                                 read: ReadFields = None, **fields: Any) -> dict[str, Any]:
        """See :meth:`Client.submit_model_check`."""
        rivals = fields.get("rivals")
        if rivals is not None and not isinstance(rivals, str):
            fields["rivals"] = ";".join(",".join(r) for r in rivals)
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       op=op, **fields)
        return await self._json("POST", "/v1/model-check/jobs", files=files, data=data)

    async def model_check_job(self, job_id: str) -> dict[str, Any]:
        return await self._json("GET", f"/v1/model-check/jobs/{job_id}")

    async def model_check_result(self, job_id: str) -> dict[str, Any]:
        return await self._json("GET", f"/v1/model-check/jobs/{job_id}/result")

    async def fit(self, log: LogSource, params: str | Mapping[str, Any], effects: str | Iterable[str], *,
                  columns: Mapping[str, Any] | None = None, steady_state: bool | None = None, read: ReadFields = None,
                  refine: bool | None = None) -> dict[str, Any]:
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       effects=effects if isinstance(effects, str) else list(effects), refine=refine)
        return await self._json("POST", "/v1/model-check/fit", files=files, data=data)

    async def submit_batch(self, missions: Iterable[BaseModel | Mapping[str, Any]],
                           idempotency_key: str | None = None) -> dict[str, Any]:
        headers = {"Idempotency-Key": idempotency_key} if idempotency_key else None
        return await self._json("POST", "/v1/batches", json={"missions": [_json(m) for m in missions]},
                                headers=headers)

    async def batch(self, batch_id: str) -> dict[str, Any]:
        return await self._json("GET", f"/v1/batches/{batch_id}")

    async def batch_results(self, batch_id: str) -> dict[str, Any]:
        return await self._json("GET", f"/v1/batches/{batch_id}/results")

    async def batch_results_csv(self, batch_id: str) -> str:
        return (await self._request("GET", f"/v1/batches/{batch_id}/results", params={"format": "csv"})).text

    async def wait_batch(self, batch_id: str, *, poll: float = 0.5, timeout: float | None = None,
                         on_progress: Callable[[dict[str, Any]], None] | None = None, reconnects: int = 5,
                         backoff: float = 0.5) -> dict[str, Any]:
        """See :meth:`Client.wait_batch`."""
        end = None if timeout is None else time.monotonic() + timeout
        failures = 0
        while True:
            try:
                status = await self.batch(batch_id)
            except TransportError:
                failures += 1
                if failures > reconnects or (end is not None and time.monotonic() > end):
                    raise
                await asyncio.sleep(self._spec.reconnect_delay(failures, backoff))
                continue
            failures = 0
            if on_progress is not None:
                on_progress(status)
            if status["status"] in ("done", "failed"):
                return status
            if end is not None and time.monotonic() > end:
                raise Timeout(f"batch {batch_id} not finished after {timeout} s")
            await asyncio.sleep(poll)
