"""Batch items on a Dask ``distributed`` cluster: the same task functions as :mod:`service.workers`."""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Hashable
from typing import Any

from service.workers import Payload, TaskFn, TaskTimeout, execute, unwrap

log = logging.getLogger("thrustshape.workers")


class DaskRunner:
    """Batch items on a Dask distributed cluster (``distributed.Client`` in asynchronous mode).

    Dask cannot kill a running task: on timeout the future is cancelled and the item fails or is
    retried, but the cluster thread finishes the call (solves bound their own CPU time).
    """

    def __init__(self, client: Any) -> None:
        self._client = client

    @classmethod
    async def connect(cls, address: str) -> DaskRunner:
        from distributed import Client

        client = await Client(address, asynchronous=True, timeout="10s")
        return cls(client)

    async def run(self, fn: TaskFn, payload: Payload, timeout: float, *, wait: bool = False,
                  deadline: float | None = None, affinity: Hashable | None = None) -> Payload:
        """``wait``, ``deadline`` and ``affinity`` are accepted for the :class:`~service.workers.Runner` protocol;
        Dask's scheduler places the task (no structure affinity: each Dask worker builds what it is given)."""
        fut = self._client.submit(execute, fn, payload, pure=False)
        try:
            outcome = await asyncio.wait_for(fut, timeout)
        except TimeoutError:
            await self._client.cancel(fut)
            log.warning("dask task %s abandoned after %g s", getattr(fn, "__name__", fn), timeout)
            raise TaskTimeout(timeout) from None
        return unwrap(outcome)

    async def close(self) -> None:
        await self._client.close()
