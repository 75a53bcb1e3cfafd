"""Background runner that drains the job store: claims queued items, runs them, stores the outcomes in groups.

Runs as one asyncio task in the app lifespan. It claims up to ``concurrency + lookahead`` items: ``concurrency``
run on the :class:`~service.workers.Runner` (local worker processes or Dask) with a hard timeout, the lookahead
waits in the pool so that a worker coming free can pick the item whose *structure* it already built (each item's
affinity key, e.g. :func:`service.tasks.structure_key`, is computed from the mission, validated with the
untrusted rule: a bad mission fails at once, naming the field, without taking a solver worker). In the server the
keys of each claimed group are computed in one call on ``key_runner`` (the fallback workers' processes:
:func:`service.tasks.affinity_keys`), never in the server process. A core error (bad
mission, infeasible problem) fails the item at once; a timeout or a crashed worker is retried up to ``attempts``
times (a worker that died before reaching the item costs no attempt).

Outcomes are written in groups: every outcome computed while the previous write ran, or within ``group_s`` of
the oldest unwritten one, lands in ONE transaction (:meth:`JobStore.record`, all or nothing); the store's state
guard makes each result land exactly once. An outcome not yet written when the server dies leaves its item
``running`` in the store; it runs again after the restart (:meth:`JobStore.recover`): a result is never lost,
only recomputed.

The store may fail for a while (locked by another process past its busy timeout, disk full, file
gone): the runner then keeps every computed outcome in memory and retries writing them, oldest first,
with exponential backoff (``backoff_s`` to ``max_backoff_s``), and claims nothing new until the
backlog is written. :meth:`health` says what the runner is doing for ``/healthz``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections import deque
from collections.abc import Hashable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

from ocp.errors import ThrustshapeError
from service.jobs import Item, JobStore, Outcome
from service.tasks import affinity_keys
from service.workers import Runner, TaskFailed, TaskFn, TaskTimeout, user_error

if TYPE_CHECKING:
    from service.tasks import KeyFn

log = logging.getLogger("thrustshape.batches")

RunnerState = Literal["running", "retrying", "stopped"]
#: a keys call's hard timeout, plus 10 ms per mission [s]; it covers the start-up of a process that is still
#: importing (a batch submitted right after the server started), which a miss would cost the group its affinity
_KEYS_TIMEOUT_S = 120.0


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
                 attempts: int, key: KeyFn | None = None, key_runner: Runner | None = None,
                 lookahead: int | None = None, group_s: float = 0.05, backoff_s: float = 0.05,
                 max_backoff_s: float = 5.0) -> None:
        """``key``: an item's affinity key from its mission (raising a ThrustshapeError fails the item);
        ``key_runner``: where the keys are computed (one background call per claimed group; default: a thread of
        this process); a keys call that fails leaves the group without affinity (its workers validate anyway);
        ``lookahead``: items claimed beyond ``concurrency`` so that a free worker has a choice (used with a
        ``key`` only; default ``concurrency``); ``group_s`` [s]: how long a finished outcome may wait for others
        to share its transaction while items are still running."""
        self._store, self._runner, self._task, self._key = store, runner, task, key
        self._key_runner = key_runner
        self._concurrency, self._timeout, self._attempts = concurrency, timeout, attempts
        self._window = concurrency + (0 if key is None else concurrency if lookahead is None else lookahead)
        self._group_s = group_s
        self._backoff = (backoff_s, max_backoff_s)
        self._wake = asyncio.Event()
        self._inflight: set[asyncio.Task[None]] = set()
        self._unsaved: deque[tuple[float, Outcome]] = deque()  # (when computed, outcome), oldest first
        self._loop_task: asyncio.Task[None] | None = None
        self._closing = False
        self._last_error: str | None = None
        self.groups = 0  # transactions that stored outcomes (for tests and benchmarks)

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
                await self._write_group()
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
                await self._write_group()
                free = self._window - len(self._inflight)
                items = await asyncio.to_thread(self._store.claim, free) if free > 0 else []
            except Exception as exc:  # the store failed: keep everything, try again later
                self._store_failed(exc)
                await asyncio.sleep(delay)
                delay = min(2.0 * delay, self._backoff[1])
                continue
            delay, self._last_error = self._backoff[0], None
            # keys in claim order, so the items reach the pool in that order
            keys = await self._keys(items)
            for item, key in zip(items, keys, strict=True):
                t = asyncio.create_task(self._run_item(item, key))
                self._inflight.add(t)
                t.add_done_callback(self._done)
            if not items or len(self._inflight) >= self._window:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._wake.wait(), timeout=1.0)
                await self._linger()

    async def _linger(self) -> None:
        """Let the oldest unwritten outcome wait up to ``group_s`` for others while items still run."""
        if self._unsaved and self._inflight:
            await asyncio.sleep(max(self._unsaved[0][0] + self._group_s - time.monotonic(), 0.0))

    async def _write_group(self) -> None:
        """Write every kept outcome in one transaction (raising, all kept, when it fails)."""
        if not self._unsaved:
            return
        group = [o for _, o in self._unsaved]
        await asyncio.to_thread(self._store.record, group)
        for _ in group:
            self._unsaved.popleft()  # outcomes computed meanwhile were appended behind the group
        self.groups += 1
        if self._last_error is not None:
            log.info("stored %d kept outcomes", len(group))

    def _store_failed(self, exc: BaseException) -> None:
        msg = f"{type(exc).__name__}: {exc}"
        if msg != self._last_error:
            log.error("job store failed (%s); %d outcomes kept in memory, retrying with backoff", msg,
                      len(self._unsaved))
        self._last_error = msg

    def _done(self, t: asyncio.Task[None]) -> None:
        self._inflight.discard(t)
        self._wake.set()

    async def _keys(self, items: list[Item]) -> list[Hashable | ThrustshapeError | None]:
        """Each item's affinity key, or the error that refuses its mission (on ``key_runner``, or in a thread)."""
        if self._key is None or not items:
            return [None] * len(items)
        if self._key_runner is None:
            return await asyncio.to_thread(lambda: [self._keyed(item) for item in items])
        todo = [i for i, item in enumerate(items) if item.mission is not None]
        keys: list[Hashable | ThrustshapeError | None] = [None] * len(items)
        try:
            out = await self._key_runner.run(affinity_keys, {"key": self._key, "missions": [items[i].mission
                                                                                              for i in todo]},
                                             _KEYS_TIMEOUT_S + 0.01 * len(todo), wait=True)
            for i, k in zip(todo, out["keys"], strict=True):
                keys[i] = user_error(*k["error"]) if "error" in k else k["key"]
        except Exception as exc:  # claimed items must run whatever happened here: without affinity then
            log.warning("affinity keys of %d items not computed (%s); they run without affinity", len(todo), exc)
            return [None] * len(items)
        return keys

    def _keyed(self, item: Item) -> Hashable | ThrustshapeError | None:
        if self._key is None or item.mission is None:
            return None
        try:
            return self._key(item.mission)
        except ThrustshapeError as exc:
            return exc
        except Exception as exc:  # no affinity then; the worker reports what is wrong with the item
            log.warning("batch %s item %d: no affinity key (%s)", item.batch_id, item.index, exc)
            return None

    async def _run_item(self, item: Item, key: Hashable | ThrustshapeError | None) -> None:
        if item.mission is None:  # claim() always loads it; a row without one cannot run
            missing: dict[str, Any] = {"type": "StoreError", "field": None, "reason": "mission missing"}
            outcome = Outcome(item.batch_id, item.index, error=missing)
        else:
            outcome = await self._outcome(item, item.mission, key)
        self._unsaved.append((time.monotonic(), outcome))

    async def _outcome(self, item: Item, mission: dict[str, Any], key: Hashable | ThrustshapeError | None) -> Outcome:
        """Run the item (on the worker its affinity key prefers); what to store."""
        try:
            if isinstance(key, ThrustshapeError):
                raise key
            result = await self._runner.run(self._task, mission, self._timeout, wait=True, affinity=key)
        except ThrustshapeError as exc:
            error: dict[str, Any] = {"type": type(exc).__name__, "field": exc.field, "reason": exc.reason}
            return Outcome(item.batch_id, item.index, error=error)
        except (TaskTimeout, TaskFailed) as exc:
            error = {"type": type(exc).__name__, "field": None, "reason": str(exc)}
            log.warning("batch %s item %d attempt %d: %s", item.batch_id, item.index, item.attempts, exc)
            blameless = isinstance(exc, TaskFailed) and exc.startup  # a worker died before reaching the item
            return Outcome(item.batch_id, item.index, error=error, retry=blameless or item.attempts < self._attempts)
        return Outcome(item.batch_id, item.index, result=result)
