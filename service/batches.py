"""Background runner that drains the job store: claims queued items, runs them, stores the outcome.

Runs as one asyncio task in the app lifespan. At most ``concurrency`` items are in flight; each runs
on the :class:`~service.workers.Runner` (local worker processes or Dask) with a hard timeout. A
core error (bad mission, infeasible problem) fails the item at once; a timeout or a crashed worker
is retried up to ``attempts`` times. Outcomes are written by :class:`~service.jobs.JobStore`, whose
state guard makes each result land exactly once.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from typing import Any

from ocp.errors import ThrustshapeError
from service.jobs import Item, JobStore
from service.workers import Runner, TaskFailed, TaskFn, TaskTimeout

log = logging.getLogger("thrustshape.batches")


class BatchRunner:
    def __init__(self, store: JobStore, runner: Runner, task: TaskFn, *, concurrency: int, timeout: float,
                 attempts: int) -> None:
        self._store, self._runner, self._task = store, runner, task
        self._concurrency, self._timeout, self._attempts = concurrency, timeout, attempts
        self._wake = asyncio.Event()
        self._inflight: set[asyncio.Task[None]] = set()
        self._loop_task: asyncio.Task[None] | None = None

    def start(self) -> None:
        self._loop_task = asyncio.create_task(self._loop(), name="thrustshape-batches")

    def wake(self) -> None:
        """New work was stored: look at the queue now instead of at the next poll."""
        self._wake.set()

    async def close(self) -> None:
        tasks = [t for t in (self._loop_task, *self._inflight) if t is not None]
        for t in tasks:
            t.cancel()
        for t in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await t

    async def _loop(self) -> None:
        while True:
            self._wake.clear()
            free = self._concurrency - len(self._inflight)
            items = await asyncio.to_thread(self._store.claim, free) if free > 0 else []
            for item in items:
                t = asyncio.create_task(self._run_item(item))
                self._inflight.add(t)
                t.add_done_callback(self._done)
            if not items or len(self._inflight) >= self._concurrency:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._wake.wait(), timeout=1.0)

    def _done(self, t: asyncio.Task[None]) -> None:
        self._inflight.discard(t)
        self._wake.set()

    async def _run_item(self, item: Item) -> None:
        error: dict[str, Any]
        assert item.mission is not None, "claimed items carry their mission"
        try:
            result = await self._runner.run(self._task, item.mission, self._timeout, wait=True)
        except ThrustshapeError as exc:
            error = {"type": type(exc).__name__, "field": exc.field, "reason": exc.reason}
            await asyncio.to_thread(self._store.fail, item.batch_id, item.index, error, False)
        except (TaskTimeout, TaskFailed) as exc:
            error = {"type": type(exc).__name__, "field": None, "reason": str(exc)}
            retry = item.attempts < self._attempts
            log.warning("batch %s item %d attempt %d: %s", item.batch_id, item.index, item.attempts, exc)
            await asyncio.to_thread(self._store.fail, item.batch_id, item.index, error, retry)
        else:
            await asyncio.to_thread(self._store.finish, item.batch_id, item.index, result)
