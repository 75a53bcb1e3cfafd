"""Asynchronous HTTP client of the thrustshape service: :class:`AsyncClient`, the twin of
:class:`clients.client.Client`."""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable, Iterable, Mapping
from typing import Any

import httpx
from pydantic import BaseModel

from clients.errors import Timeout, TransportError
from clients.http import DEFAULT_TIMEOUT, LogSource, ReadFields, _json, _qs, _Spec, model_check_form


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
                    read: ReadFields = None, max_logging_skew: float | None = None) -> dict[str, Any]:
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       max_logging_skew=max_logging_skew)
        return await self._json("POST", "/v1/model-check/check", files=files, data=data)

    async def check_report(self, log: LogSource, params: str | Mapping[str, Any], *,
                           columns: Mapping[str, Any] | None = None, steady_state: bool | None = None,
                           read: ReadFields = None, max_logging_skew: float | None = None) -> str:
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       max_logging_skew=max_logging_skew)
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
                  refine: bool | None = None, max_logging_skew: float | None = None) -> dict[str, Any]:
        files, data = model_check_form(log, params, columns=columns, steady_state=steady_state, **dict(read or {}),
                                       effects=effects if isinstance(effects, str) else list(effects), refine=refine,
                                       max_logging_skew=max_logging_skew)
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
