"""HTTP client of the thrustshape service: :class:`Client` (sync) and :class:`AsyncClient`, on httpx.

Both wrap an ``httpx`` client; pass ``transport=`` to talk to an app in-process (e.g.
``httpx.ASGITransport(app)``) or through any other httpx transport. A 503 is retried up to
``retries`` times, waiting what the server's ``Retry-After`` says (capped by ``max_retry_wait``);
``wait_batch`` polls through dropped connections (``reconnects`` in a row, with backoff).
Errors form a tree (:mod:`clients.errors`: :class:`ClientError` at the root, :class:`TransportError` when no
HTTP answer came, :class:`APIError` with the parsed problem+json when the server answered with an error), so
callers catch as broadly or as narrowly as they need; every name is importable from here.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import httpx
from pydantic import BaseModel

from clients.async_client import AsyncClient
from clients.errors import (
    APIError,
    BadRequest,
    ClientError,
    ComputationTimeout,
    InvalidInput,
    MalformedResponse,
    NotFound,
    PayloadTooLarge,
    ServerBusy,
    ServerError,
    Timeout,
    TransportError,
    Unauthorized,
)
from clients.http import DEFAULT_TIMEOUT, LogSource, ReadFields, _json, _qs, _Spec, model_check_form

__all__ = ["APIError", "AsyncClient", "BadRequest", "Client", "ClientError", "ComputationTimeout", "InvalidInput",
           "MalformedResponse", "NotFound", "PayloadTooLarge", "ServerBusy", "ServerError", "Timeout",
           "TransportError", "Unauthorized", "model_check_form"]


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
              steady_state: bool | None = None, read: ReadFields = None, max_logging_skew: float | None = None
              ) -> dict[str, Any]:
        """Model check: where the model fails on ``log`` (see :func:`model_check_form` for the arguments)."""
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       max_logging_skew=max_logging_skew)
        return self._request("POST", "/v1/model-check/check", files=files, data=data).json()

    def check_report(self, log: LogSource, params: str | Mapping[str, Any], *,
                     columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                     read: ReadFields = None, max_logging_skew: float | None = None) -> str:
        """The self-contained HTML report of :meth:`check`."""
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       max_logging_skew=max_logging_skew)
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
        self._poll(lambda: self.model_check_job(job_id), f"model-check job {job_id}", poll, timeout, reconnects,
                   backoff, None if on_progress is None else
                   lambda st: on_progress(1.0 if st["status"] == "done" else float(st["progress"])))
        return self.model_check_result(job_id)

    def design_experiment(self, log: LogSource, params: str | Mapping[str, Any], *,
                          on_progress: Callable[[float], None] | None = None, timeout: float | None = None,
                          **fields: Any) -> dict[str, Any]:
        """Diagnose ``log`` and design the experiment that settles it (a job; see :meth:`submit_model_check` for
        ``fields``); returns the design with its ``mission`` and its ``diagnosis``."""
        job = self.submit_model_check("design", log, params, **fields)
        return self.wait_model_check(job["id"], timeout=timeout, on_progress=on_progress)

    def fit(self, log: LogSource, params: str | Mapping[str, Any], effects: str | Iterable[str], *,
            columns: Mapping[str, Any] | None = None, steady_state: bool | None = None, read: ReadFields = None,
            refine: bool | None = None, max_logging_skew: float | None = None) -> dict[str, Any]:
        """Add ``effects`` and refit; the answer's ``calibrated_params`` is the calibrated parameter mapping."""
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       effects=effects if isinstance(effects, str) else list(effects), refine=refine,
                                       max_logging_skew=max_logging_skew)
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
        return self._poll(lambda: self.batch(batch_id), f"batch {batch_id}", poll, timeout, reconnects, backoff,
                          on_progress)

    def _poll(self, fetch: Callable[[], dict[str, Any]], what: str, poll: float, timeout: float | None,
              reconnects: int, backoff: float,
              on_progress: Callable[[dict[str, Any]], None] | None) -> dict[str, Any]:
        """``fetch()`` a job's status until it is done or failed (returned), through ``reconnects`` dropped
        connections in a row (waits doubling from ``backoff`` [s]); :class:`Timeout` after ``timeout`` [s]."""
        end = None if timeout is None else time.monotonic() + timeout
        failures = 0
        while True:
            try:
                status = fetch()
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
                raise Timeout(f"{what} not finished after {timeout} s")
            time.sleep(poll)
