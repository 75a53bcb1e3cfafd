"""What the sync and async clients share: the default timeout, request bodies, the retry policy."""

from __future__ import annotations

import contextlib
import json
import os
from collections.abc import Iterable, Iterator, Mapping
from pathlib import Path
from typing import Any

import httpx
from pydantic import BaseModel

from clients.errors import MalformedResponse, Timeout, TransportError, _error, _retry_after

DEFAULT_TIMEOUT = httpx.Timeout(60.0, connect=5.0)


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
    ``resample``, ``negate`` of :class:`ocp.logs.ReadOptions`); ``None`` values are left out. ``steady_state=None``: the
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
