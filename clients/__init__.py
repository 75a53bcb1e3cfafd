"""thrustshape clients: the ``thrustshape`` command line (``clients.cli``) and the HTTP client."""

from clients.client import (
    APIError,
    AsyncClient,
    BadRequest,
    Client,
    ClientError,
    ComputationTimeout,
    InvalidInput,
    NotFound,
    PayloadTooLarge,
    ServerBusy,
    ServerError,
    Timeout,
    TransportError,
    Unauthorized,
)

__all__ = ["APIError", "AsyncClient", "BadRequest", "Client", "ClientError", "ComputationTimeout", "InvalidInput",
           "NotFound", "PayloadTooLarge", "ServerBusy", "ServerError", "Timeout", "TransportError", "Unauthorized"]
