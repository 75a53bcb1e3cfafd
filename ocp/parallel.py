"""Independent pieces of one computation run on the machine's cores, in threads: NumPy's array operations and LAPACK
release the interpreter lock, so pieces that are array work overlap (the ripple's period search: each count's columns,
their view and fit, :func:`ocp.identify.ripple.pick_periods`). A piece must be NumPy/SciPy array work on arrays it
does not share for writing: no CasADi call (creating CasADi matrices, which a Function's call does for its results, is
not thread-safe: casadi/casadi#3518), no solver.

* :func:`threads`: how many, read at each call from ``$THRUSTSHAPE_THREADS`` (a positive integer; ``1`` runs every
  piece in the calling thread), else the cores this process may run on, at most :data:`MAX_THREADS`. A free run's
  segments take the same count of CasADi's own threads, inside one call (:func:`ocp.identify.predict.free_run`).
* :func:`ordered`: a function over items, the results yielded in the items' order, so that a caller reducing them
  (a running best, a first minimum) does exactly what a plain loop does; at most ``threads + 1`` pieces are started
  ahead of the one being consumed, so results waiting to be consumed stay few however many items there are.
* :func:`one_blas_thread` (and :func:`own_threads`, the decorator of the entry points that use :func:`ordered`): the
  BLAS library's own threads held to one while a computation runs that parallelises its pieces itself. On the
  identifier's products (Gram matrices of a few dozen columns over 10^4-10^5 rows, small least squares) OpenBLAS's
  threads cost more than they save (blind rig 109, 104,000 rows: 27 s of CPU for 20 s of wall time with them, 15 s and
  18.5 s without), and with one BLAS thread a piece's arithmetic, hence its rounding, is the same however many threads
  run the pieces and however many cores the machine has.
"""

from __future__ import annotations

import functools
import os
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from contextlib import contextmanager
from typing import ParamSpec, TypeVar

from threadpoolctl import threadpool_limits

from ocp.errors import ParameterError

T = TypeVar("T")
R = TypeVar("R")
P = ParamSpec("P")

#: the most threads :func:`threads` gives by default (the pieces' arrays compete for memory bandwidth beyond a few)
MAX_THREADS = 4


def threads() -> int:
    """Threads for independent pieces: ``$THRUSTSHAPE_THREADS`` if set (a positive integer; anything else raises
    :class:`~ocp.errors.ParameterError` naming it), else the cores this process may run on, at most
    :data:`MAX_THREADS`."""
    text = os.environ.get("THRUSTSHAPE_THREADS", "").strip()
    if text:
        n = int(text) if text.isdecimal() else 0
        if n < 1:
            raise ParameterError("THRUSTSHAPE_THREADS", f"must be a positive integer, not {text!r}")
        return n
    try:
        cores = len(os.sched_getaffinity(0))
    except AttributeError:  # (not on Linux)
        cores = os.cpu_count() or 1
    return max(1, min(MAX_THREADS, cores))


def ordered(fn: Callable[[T], R], items: Iterable[T], workers: int | None = None) -> Iterator[R]:
    """``fn(item)`` for each item, yielded in the items' order, computed by ``workers`` threads (default
    :func:`threads`; one: in the calling thread, one after another). An exception raised by ``fn`` is raised here,
    at its item's turn, after the pieces already started have finished."""
    n = threads() if workers is None else workers
    if n <= 1:
        yield from map(fn, items)
        return
    with ThreadPoolExecutor(max_workers=n, thread_name_prefix="thrustshape") as pool:
        pending: deque[Future[R]] = deque()
        for item in items:
            pending.append(pool.submit(fn, item))
            if len(pending) > n:
                yield pending.popleft().result()
        while pending:
            yield pending.popleft().result()


@contextmanager
def one_blas_thread() -> Iterator[None]:
    """The BLAS libraries loaded in this process run single-threaded inside the block (their thread count is
    restored after; module doc)."""
    with threadpool_limits(limits=1, user_api="blas"):
        yield


def own_threads(fn: Callable[P, R]) -> Callable[P, R]:
    """``fn``, an entry point whose work runs pieces through :func:`ordered` (the model check's ``check``, ``fit``
    and ``diagnose``), called with the thread setting checked first (:func:`threads`) and BLAS held to one thread
    (:func:`one_blas_thread`): the same rounding in each, whatever the cores."""
    @functools.wraps(fn)
    def call(*args: P.args, **kwargs: P.kwargs) -> R:
        threads()
        with one_blas_thread():
            return fn(*args, **kwargs)

    return call
