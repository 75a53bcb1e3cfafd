"""Pure ASGI middleware: refuse request bodies over ``max_body_bytes`` (413) before they are buffered, and
requests without the API key (401) before their body is read.

Paths under a prefix of ``uploads`` (e.g. the model-check log uploads) get their own limit, and the
413 names that upload's form field instead of ``body``.
"""

from __future__ import annotations

import hmac
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


async def _reject(send: Send, status: int, title: str, detail: str, field: str | None = None,
                  headers: list[tuple[bytes, bytes]] | None = None) -> None:
    body: dict[str, object] = {"type": "about:blank", "title": title, "status": status, "detail": detail}
    if field is not None:
        body.update(field=field, reason=detail)
    data = json.dumps(body).encode()
    await send({"type": "http.response.start", "status": status,
                "headers": [(b"content-type", PROBLEM.encode()), (b"content-length", str(len(data)).encode()),
                            (b"connection", b"close"), *(headers or [])]})
    await send({"type": "http.response.body", "body": data})


class ApiKeyGate:
    """401 for a request without ``Authorization: Bearer <key>`` before anything reads its body: a client
    without the key cannot make the server parse a JSON body or receive a 30 MB upload. Paths in
    ``public`` (exact) or under ``public_prefixes`` pass (liveness, the page and its static files)."""

    def __init__(self, app: ASGIApp, key: bytes | None, public: frozenset[str],
                 public_prefixes: tuple[str, ...]) -> None:
        self.app, self.key, self.public, self.prefixes = app, key, public, public_prefixes

    def _allowed(self, scope: Scope) -> bool:
        path = str(scope.get("path", ""))
        if self.key is None or path in self.public or path.startswith(self.prefixes):
            return True
        header = dict(scope.get("headers") or []).get(b"authorization", b"")
        scheme, _, token = header.partition(b" ")
        return scheme.lower() == b"bearer" and hmac.compare_digest(token.strip(), self.key)

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http" or self._allowed(scope):
            await self.app(scope, receive, send)
            return
        await _reject(send, 401, "Unauthorized", "missing or wrong API key (Authorization: Bearer <key>)",
                      headers=[(b"www-authenticate", b"Bearer")])
