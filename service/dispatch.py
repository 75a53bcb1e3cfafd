"""Which idle worker takes which waiting call: urgency first, then structure affinity, and nothing starves.

A call may carry an *affinity key*: what its worker holds afterwards and would otherwise rebuild, e.g. the
structure of a collocation program (:func:`service.tasks.structure_key`; a worker process caches the programs
it built, :data:`ocp.optimize.collocation.CACHE_SIZE` of them). The dispatcher remembers, per worker, the keys
of its last ``slots`` calls (least recently used forgotten, as the worker's cache does). Whenever a worker is
idle and a call waits, it pairs them by rank, best first (then the oldest call, then the worker holding the
fewest keys, whose cache loses least):

0. a call with a deadline (``urgent``): a batch never makes an interactive request wait;
1. a call passed over ``patience`` times, whatever its key: nothing starves;
2. a call whose key the worker holds: no build;
3. a call without a key, or whose key no worker holds or is running: a build nobody else does;
4. a call whose key only busy workers hold, when each of them has more than ``crowd`` waiting calls of keys it
   holds: a second build pays off against that queue.

Any other call waits for the worker that holds its key (a duplicate build costs more than a short queue).

Single-threaded: use it from the event loop only.
"""

from __future__ import annotations

import asyncio
import itertools
from collections import Counter, OrderedDict
from collections.abc import Hashable, Sequence
from dataclasses import dataclass, field
from typing import Generic, TypeVar

W = TypeVar("W", bound=Hashable)
_SEQ = itertools.count()


@dataclass(eq=False)
class _Waiter(Generic[W]):
    future: asyncio.Future[W]
    key: Hashable | None
    urgent: bool
    skipped: int = 0
    seq: int = field(default_factory=lambda: next(_SEQ))


class Dispatcher(Generic[W]):
    """Idle workers and the calls waiting for one; see the module doc.

    A pairing looks at a few candidates, not at every waiting call: the oldest urgent call and the oldest
    call of each key. Any other call ranks no better than the oldest of its key and is younger (a call older
    than another was passed over at least as often, so it runs out of ``patience`` first). A batch of
    thousands of waiting items then costs each pairing a pass over the keys and the workers, not over the
    items (tested against the rule written out for every call).
    """

    def __init__(self, workers: Sequence[W], slots: int = 8, patience: int = 32, crowd: int = 8) -> None:
        """``slots``: keys remembered per worker (its cache size); ``patience``: how often a waiting call may be
        passed over; ``crowd``: a holder's queue beyond which another worker builds its key too."""
        self._idle: list[W] = list(workers)
        self._waiting: list[_Waiter[W]] = []  # oldest first
        self._urgent: list[_Waiter[W]] = []  # the urgent ones among them, oldest first
        self._by_key: dict[Hashable | None, list[_Waiter[W]]] = {}  # the others by key, oldest first
        self._queued: Counter[Hashable | None] = Counter()  # waiting calls per key
        self._held: dict[W, OrderedDict[Hashable, None]] = {w: OrderedDict() for w in workers}
        self._running: dict[W, Hashable | None] = {}
        self.slots, self.patience, self.crowd = slots, patience, crowd

    def holds(self, worker: W) -> tuple[Hashable, ...]:
        """The keys ``worker`` is remembered to hold, least recently used first."""
        return tuple(self._held[worker])

    @property
    def waiting(self) -> int:
        """Calls waiting for a worker."""
        return len(self._waiting)

    async def get(self, key: Hashable | None = None, urgent: bool = False) -> W:
        """A worker for a call with affinity ``key`` (see the module doc for which); waits until one is paired
        with it. A caller cancelled while waiting (e.g. by ``asyncio.wait_for``) leaves no worker behind."""
        waiter: _Waiter[W] = _Waiter(asyncio.get_running_loop().create_future(), key, urgent)
        self._waiting.append(waiter)
        (self._urgent if urgent else self._by_key.setdefault(key, [])).append(waiter)
        self._queued[key] += 1
        self._match()
        try:
            return await waiter.future
        except asyncio.CancelledError:
            if waiter.future.done() and not waiter.future.cancelled():
                self.put(waiter.future.result())  # paired just as the caller gave up: pass it on
            elif waiter in self._waiting:
                self._drop(waiter)
            raise

    def put(self, worker: W) -> None:
        """``worker`` is free: pair it with a waiting call, or keep it idle."""
        self._running.pop(worker, None)
        self._idle.append(worker)
        self._match()

    def remember(self, worker: W, key: Hashable | None) -> None:
        """``worker`` finished a call with ``key``: it holds it now (most recently used)."""
        if key is None:
            return
        held = self._held[worker]
        held[key] = None
        held.move_to_end(key)
        while len(held) > self.slots:
            held.popitem(last=False)

    def forget(self, worker: W) -> None:
        """``worker``'s process was replaced: it holds nothing."""
        self._held[worker].clear()

    def _drop(self, waiter: _Waiter[W]) -> None:
        self._waiting.remove(waiter)
        if waiter.urgent:
            self._urgent.remove(waiter)
        else:
            group = self._by_key[waiter.key]
            group.remove(waiter)
            if not group:
                del self._by_key[waiter.key]
        self._queued[waiter.key] -= 1
        if not self._queued[waiter.key]:
            del self._queued[waiter.key]

    def _candidates(self) -> list[_Waiter[W]]:
        """The calls that can win a pairing (class doc), after dropping any whose caller is gone."""
        while self._urgent and self._urgent[0].future.done():
            self._drop(self._urgent[0])
        for group in list(self._by_key.values()):
            while group and group[0].future.done():
                self._drop(group[0])
        return [*self._urgent[:1], *(g[0] for g in self._by_key.values() if g)]

    def _match(self) -> None:
        """Pair idle workers with waiting calls, best rank first, until no acceptable pair is left."""
        while self._idle and self._waiting:
            candidates = self._candidates()
            holds = {w: set(self._held[w]) | ({self._running[w]} if w in self._running else set()) for w in self._held}
            backlog = {w: sum(self._queued[k] for k in keys) for w, keys in holds.items()}
            # per key: the shortest queue among the workers that hold it (absent: nobody holds it)
            shortest: dict[Hashable | None, int] = {}
            for w, keys in holds.items():
                for k in keys:
                    shortest[k] = min(shortest.get(k, backlog[w]), backlog[w])
            pairs = [(rank, x.seq, len(self._held[w]), i, x, w) for i, w in enumerate(self._idle)
                     for x in candidates if (rank := self._rank(w, x, shortest)) is not None]
            if not pairs:
                return
            *_, waiter, worker = min(pairs, key=lambda p: p[:4])
            for x in self._waiting:
                if x is waiter:
                    break
                x.skipped += 1
            self._drop(waiter)
            self._idle.remove(worker)
            self._running[worker] = waiter.key
            waiter.future.set_result(worker)

    def _rank(self, worker: W, x: _Waiter[W], shortest: dict[Hashable | None, int]) -> int | None:
        if x.urgent:
            return 0
        if x.skipped >= self.patience:
            return 1
        if x.key is None:
            return 3
        if x.key in self._held[worker]:
            return 2
        if x.key not in shortest:
            return 3
        return 4 if shortest[x.key] > self.crowd else None
