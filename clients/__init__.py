"""thrustshape clients: the ``thrustshape`` command line (``clients.cli``) and the HTTP client.

The client's names are imported on first use (PEP 562), so the command line does not load httpx
for commands that never talk to a server.
"""

from __future__ import annotations

from typing import Any

__all__ = ["APIError", "AsyncClient", "BadRequest", "Client", "ClientError", "ComputationTimeout", "InvalidInput",
           "MalformedResponse", "NotFound", "PayloadTooLarge", "ServerBusy", "ServerError", "Timeout",
           "TransportError", "Unauthorized"]


def __getattr__(name: str) -> Any:
    if name in __all__:
        from clients import client

        return getattr(client, name)
    raise AttributeError(f"module 'clients' has no attribute {name!r}")
