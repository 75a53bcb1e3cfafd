"""One per-process LRU cache of built programs (the Radau program's and the flat program's), thread-safe.

A build happens outside the lock (seconds for a Radau program): two threads asking for one new key at once may
both build it; the second result replaces the first. ``on_build`` hears ``"build"`` before a build and
``"built"`` once the program is cached (:attr:`ocp.optimize.collocation.SolveContext.on_build`).
"""

from __future__ import annotations

import threading
from collections.abc import Callable, Hashable
from typing import Generic, TypeVar

P = TypeVar("P")


class ProgramCache(Generic[P]):
    """At most ``size`` programs, least recently used evicted."""

    def __init__(self, size: int) -> None:
        self.size = size
        self._items: dict[Hashable, P] = {}
        self._lock = threading.Lock()

    def get(self, key: Hashable, build: Callable[[], P],
            on_build: Callable[[str], None] | None = None) -> tuple[P, bool]:
        """The program of ``key``, built by ``build()`` on first use; and whether this call built it."""
        with self._lock:
            prog = self._items.pop(key, None)
            if prog is not None:
                self._items[key] = prog  # most recently used last
                return prog, False
        if on_build is not None:
            on_build("build")
        prog = build()
        with self._lock:
            while len(self._items) >= self.size:
                self._items.pop(next(iter(self._items)))
            self._items[key] = prog
        if on_build is not None:
            on_build("built")
        return prog, True

    def clear(self) -> None:
        """Forget every built program (benchmarks measure build cost)."""
        with self._lock:
            self._items.clear()
