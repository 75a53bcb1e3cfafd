"""Pure ASGI middleware: refuse request bodies over ``max_body_bytes`` (413) before they are buffered.

Paths under a prefix of ``uploads`` (e.g. the model-check log uploads) get their own limit, and the
413 names that upload's form field instead of ``body``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping

from starlette.types import ASGIApp, Message, Receive, Scope, Send

from service.api.problems import PROBLEM, BodyTooLarge


class BodyLimit:
    """413 on a ``Content-Length`` over the limit; for chunked bodies, stop reading once over it."""

    def __init__(self, app: ASGIApp, max_bytes: int, uploads: Mapping[str, tuple[int, str]] | None = None) -> None:
        """``uploads``: path prefix -> (limit [bytes], field named in the 413)."""
        self.app, self.max_bytes, self.uploads = app, max_bytes, dict(uploads or {})

    def _limit(self, path: str) -> tuple[int, str]:
        for prefix, (limit, field) in self.uploads.items():
            if path.startswith(prefix):
                return limit, field
        return self.max_bytes, "body"

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        max_bytes, field = self._limit(str(scope.get("path", "")))
        length = dict(scope.get("headers") or []).get(b"content-length")
        if length is not None:
            try:
                declared = int(length)
            except ValueError:
                await _reject(send, 400, "Bad request", "Content-Length is not an integer")
                return
            if declared > max_bytes:
                await _reject(send, 413, "Request too large", f"request body larger than {max_bytes} bytes",
                              field=field)
                return
        seen = 0

        async def limited() -> Message:
            nonlocal seen
            msg = await receive()
            if msg["type"] == "http.request":
                seen += len(msg.get("body", b""))
                if seen > max_bytes:
                    raise BodyTooLarge(max_bytes, field)
            return msg

        await self.app(scope, limited, send)


async def _reject(send: Send, status: int, title: str, detail: str, field: str | None = None) -> None:
    body: dict[str, object] = {"type": "about:blank", "title": title, "status": status, "detail": detail}
    if field is not None:
        body.update(field=field, reason=detail)
    data = json.dumps(body).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", PROBLEM.encode()), (b"content-length", str(len(data)).encode()),
                            (b"connection", b"close")]})
    await send({"type": "http.response.body", "body": data})
