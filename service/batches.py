"""Background runner that drains the job store: claims queued items, runs them, stores the outcome.

Runs as one asyncio task in the app lifespan. At most ``concurrency`` items are in flight; each runs
on the :class:`~service.workers.Runner` (local worker processes or Dask) with a hard timeout. A
core error (bad mission, infeasible problem) fails the item at once; a timeout or a crashed worker
is retried up to ``attempts`` times (a worker that died before reaching the item costs no attempt).
Outcomes are written by :class:`~service.jobs.JobStore`, whose
state guard makes each result land exactly once.

The store may fail for a while (locked by another process past its busy timeout, disk full, file
gone): the runner then keeps every computed outcome in memory and retries writing it, oldest first,
with exponential backoff (``backoff_s`` to ``max_backoff_s``), and claims nothing new until the
backlog is written. An item whose outcome is never written stays ``running`` in the store and runs
again after a restart (:meth:`JobStore.recover`): nothing is lost, nothing lands twice. :meth:`health`
says what the runner is doing for ``/healthz``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

from ocp.errors import ThrustshapeError
from service.jobs import Item, JobStore
from service.workers import Runner, TaskFailed, TaskFn, TaskTimeout

log = logging.getLogger("thrustshape.batches")

RunnerState = Literal["running", "retrying", "stopped"]


@dataclass(frozen=True)
class RunnerHealth:
    """What :meth:`BatchRunner.health` reports: ``state``, the outcomes computed but not yet stored, items in
    flight, and the last store error (None when the last store operation succeeded)."""

    state: RunnerState
    unsaved: int
    inflight: int
    last_error: str | None


class BatchRunner:
    def __init__(self, store: JobStore, runner: Runner, task: TaskFn, *, concurrency: int, timeout: float,
                 attempts: int, backoff_s: float = 0.05, max_backoff_s: float = 5.0) -> None:
        self._store, self._runner, self._task = store, runner, task
        self._concurrency, self._timeout, self._attempts = concurrency, timeout, attempts
        self._backoff = (backoff_s, max_backoff_s)
        self._wake = asyncio.Event()
        self._inflight: set[asyncio.Task[None]] = set()
        self._unsaved: deque[tuple[str, Callable[[], Any]]] = deque()  # (what, store write) in order
        self._loop_task: asyncio.Task[None] | None = None
        self._closing = False
        self._last_error: str | None = None

    def start(self) -> None:
        self._loop_task = asyncio.create_task(self._loop(), name="thrustshape-batches")
        self._loop_task.add_done_callback(self._loop_ended)

    def wake(self) -> None:
        """New work was stored: look at the queue now instead of at the next poll."""
        self._wake.set()

    def health(self) -> RunnerHealth:
        alive = self._loop_task is not None and not self._loop_task.done()
        state: RunnerState = "stopped" if not alive else "retrying" if self._last_error else "running"
        return RunnerHealth(state, len(self._unsaved), len(self._inflight), self._last_error)

    async def close(self) -> None:
        self._closing = True
        tasks = [t for t in (self._loop_task, *self._inflight) if t is not None]
        for t in tasks:
            t.cancel()
        for t in tasks:
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await t
        if self._unsaved:  # one last try; what still fails runs again after the restart
            with contextlib.suppress(Exception):
                await asyncio.to_thread(self._flush_sync)
            if self._unsaved:
                log.error("%d batch outcomes could not be stored; their items run again after a restart",
                          len(self._unsaved))

    def _loop_ended(self, t: asyncio.Task[None]) -> None:
        if self._closing or t.cancelled():
            return
        log.error("batch runner loop ended (%r); restarting it", t.exception())
        self.start()

    async def _loop(self) -> None:
        delay = self._backoff[0]
        while True:
            self._wake.clear()
            try:
                await asyncio.to_thread(self._flush_sync)
                free = self._concurrency - len(self._inflight)
                items = await asyncio.to_thread(self._store.claim, free) if free > 0 else []
            except Exception as exc:  # the store failed: keep everything, try again later
                self._store_failed(exc)
                await asyncio.sleep(delay)
                delay = min(2.0 * delay, self._backoff[1])
                continue
            delay, self._last_error = self._backoff[0], None
            for item in items:
                t = asyncio.create_task(self._run_item(item))
                self._inflight.add(t)
                t.add_done_callback(self._done)
            if not items or len(self._inflight) >= self._concurrency:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._wake.wait(), timeout=1.0)

    def _store_failed(self, exc: BaseException) -> None:
        msg = f"{type(exc).__name__}: {exc}"
        if msg != self._last_error:
            log.error("job store failed (%s); %d outcomes kept in memory, retrying with backoff", msg,
                      len(self._unsaved))
        self._last_error = msg

    def _flush_sync(self) -> None:
        """Write kept outcomes oldest first; stop (raising) at the first that fails."""
        while self._unsaved:
            what, write = self._unsaved[0]
            write()
            self._unsaved.popleft()
            log.info("stored the kept outcome of %s", what)

    def _done(self, t: asyncio.Task[None]) -> None:
        self._inflight.discard(t)
        self._wake.set()

    async def _run_item(self, item: Item) -> None:
        if item.mission is None:  # claim() always loads it; a row without one cannot run
            missing: dict[str, Any] = {"type": "StoreError", "field": None, "reason": "mission missing"}
            write = self._failer(item, missing, False)
        else:
            write = await self._outcome(item, item.mission)
        what = f"batch {item.batch_id} item {item.index}"
        if self._unsaved:  # keep the order: an older outcome is still waiting
            self._unsaved.append((what, write))
            return
        try:
            await asyncio.to_thread(write)
        except Exception as exc:
            self._unsaved.append((what, write))
            self._store_failed(exc)
            self._wake.set()

    async def _outcome(self, item: Item, mission: dict[str, Any]) -> Callable[[], Any]:
        """Run the item; the store write that records its outcome."""
        error: dict[str, Any]
        try:
            result = await self._runner.run(self._task, mission, self._timeout, wait=True)
        except ThrustshapeError as exc:
            error = {"type": type(exc).__name__, "field": exc.field, "reason": exc.reason}
            return self._failer(item, error, False)
        except (TaskTimeout, TaskFailed) as exc:
            error = {"type": type(exc).__name__, "field": None, "reason": str(exc)}
            log.warning("batch %s item %d attempt %d: %s", item.batch_id, item.index, item.attempts, exc)
            blameless = isinstance(exc, TaskFailed) and exc.startup  # a worker died before reaching the item
            return self._failer(item, error, blameless or item.attempts < self._attempts)
        return lambda: self._store.finish(item.batch_id, item.index, result)

    def _failer(self, item: Item, error: dict[str, Any], retry: bool) -> Callable[[], Any]:
        return lambda: self._store.fail(item.batch_id, item.index, error, retry)
