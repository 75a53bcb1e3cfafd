"""Worker processes for CPU-bound solves, and the Dask alternative for batch items.

:class:`WorkerPool` owns ``n`` long-lived processes (spawned, so each has its own solver cache and
nothing is shared with the server's threads). A task is any importable top-level function
``fn(payload: dict) -> dict``; it travels by reference over a pipe. Each call has a hard wall-clock
timeout: when it expires the process is killed and replaced, so a runaway solve costs one process,
never the server. Calls beyond ``workers + queue_size`` are refused at once with :class:`QueueFull`
(the API answers 503 + Retry-After).

Errors cross the process boundary as data, not as pickled exceptions: a
:class:`~ocp.errors.ThrustshapeError` raised by a task comes back as the same class with its
``field`` and ``reason``; anything else becomes :class:`TaskFailed`.

:class:`DaskRunner` runs the same task functions on a ``distributed`` cluster (batch items only).
"""

from __future__ import annotations

import asyncio
import contextlib
import importlib
import multiprocessing as mp
import signal
from collections.abc import Callable, Sequence
from concurrent.futures import ThreadPoolExecutor
from multiprocessing.connection import Connection
from typing import Any, Literal, Protocol

import ocp.errors as errors

Payload = dict[str, Any]
TaskFn = Callable[[Payload], Payload]
Outcome = tuple[Literal["ok", "user-error", "crash"], Any]

_STARTUP_TIMEOUT_S = 120.0


class QueueFull(Exception):
    """Every worker is busy and the wait queue is full; retry after ``retry_after`` seconds."""

    def __init__(self, retry_after: int) -> None:
        self.retry_after = retry_after
        super().__init__(f"all workers busy and queue full; retry after {retry_after} s")


class TaskTimeout(Exception):
    """A task exceeded its hard timeout; its process was killed (or, on Dask, the task abandoned)."""

    def __init__(self, timeout: float) -> None:
        self.timeout = timeout
        super().__init__(f"task exceeded its {timeout:g} s timeout")


class TaskFailed(Exception):
    """A task raised an unexpected exception or its process died; ``detail`` says what happened."""

    def __init__(self, detail: str) -> None:
        self.detail = detail
        super().__init__(detail)


def execute(fn: TaskFn, payload: Payload) -> Outcome:
    """Run ``fn(payload)`` and turn every exception into data (runs inside a worker)."""
    try:
        return "ok", fn(payload)
    except errors.ThrustshapeError as exc:
        return "user-error", (type(exc).__name__, exc.field, exc.reason)
    except Exception as exc:  # a worker must answer, whatever the task did
        return "crash", f"{type(exc).__name__}: {exc}"


def unwrap(outcome: Outcome) -> Payload:
    """The task's result, or the exception it stands for (a ThrustshapeError leaf or TaskFailed)."""
    kind, value = outcome
    if kind == "ok":
        return value
    if kind == "user-error":
        name, field, reason = value
        cls = getattr(errors, name, errors.ThrustshapeError)
        if not (isinstance(cls, type) and issubclass(cls, errors.ThrustshapeError)):
            cls = errors.ThrustshapeError
        raise cls(field, reason)
    raise TaskFailed(str(value))


def _worker_main(conn: Connection, preload: Sequence[str]) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the server decides when workers stop
    for name in preload:
        with contextlib.suppress(ImportError):
            importlib.import_module(name)
    conn.send(("ready", None))
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg is None:
            return
        fn, payload = msg
        conn.send(execute(fn, payload))


class _Worker:
    """One solver process and the parent's end of its pipe; used by one thread at a time."""

    def __init__(self, ctx: Any, preload: Sequence[str]) -> None:
        self._ctx, self._preload = ctx, tuple(preload)
        self._ready = False
        self.conn: Connection
        self.proc: Any
        self._spawn()

    def _spawn(self) -> None:
        parent, child = self._ctx.Pipe()
        self.proc = self._ctx.Process(target=_worker_main, args=(child, self._preload), daemon=True,
                                      name="thrustshape-worker")
        self.proc.start()
        child.close()
        self.conn, self._ready = parent, False

    def _await_ready(self) -> None:
        if self._ready:
            return
        if not self.conn.poll(_STARTUP_TIMEOUT_S):
            self.restart()
            raise TaskFailed("worker process did not start")
        try:
            self.conn.recv()
        except EOFError:
            self.restart()
            raise TaskFailed("worker process died while starting") from None
        self._ready = True

    def call(self, fn: TaskFn, payload: Payload, timeout: float) -> Outcome:
        """Blocking: run one task, kill + respawn the process on timeout or death."""
        self._await_ready()
        try:
            self.conn.send((fn, payload))
            if not self.conn.poll(timeout):
                self.restart()
                raise TaskTimeout(timeout)
            return self.conn.recv()
        except (EOFError, OSError, BrokenPipeError):
            code = self.proc.exitcode
            self.restart()
            raise TaskFailed(f"worker process died (exit code {code})") from None

    def restart(self) -> None:
        self.kill()
        self._spawn()

    def kill(self) -> None:
        if self.proc.is_alive():
            self.proc.kill()
        self.proc.join(5.0)
        self.conn.close()

    def stop(self) -> None:
        with contextlib.suppress(OSError, BrokenPipeError):
            self.conn.send(None)
        self.proc.join(2.0)
        self.kill()


class WorkerPool:
    """``workers`` solver processes behind an asyncio front; see the module doc.

    Create and close it inside the app lifespan (it starts processes and a thread pool).
    """

    def __init__(self, workers: int, queue_size: int, retry_after: int,
                 preload: Sequence[str] = ("ocp.analytic", "ocp.fallback", "ocp.mission")) -> None:
        self.size = workers
        self.capacity = workers + queue_size
        self.retry_after = retry_after
        self._ctx = mp.get_context("spawn")
        self._workers = [_Worker(self._ctx, preload) for _ in range(workers)]
        self._threads = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="thrustshape-call")
        self._idle: asyncio.Queue[_Worker] = asyncio.Queue()
        for w in self._workers:
            self._idle.put_nowait(w)
        self._pending = 0

    @property
    def pending(self) -> int:
        """Calls admitted and not finished (running + waiting)."""
        return self._pending

    async def run(self, fn: TaskFn, payload: Payload, timeout: float, *, wait: bool = False,
                  deadline: float | None = None) -> Payload:
        """Run ``fn(payload)`` in a worker with a hard ``timeout`` [s].

        ``wait=True`` waits for a free worker instead of raising :class:`QueueFull`; ``deadline`` (event
        loop time) also counts the wait for a worker: the task gets what is left of it.
        """
        if not wait and self._pending >= self.capacity:
            raise QueueFull(self.retry_after)
        self._pending += 1
        try:
            worker = await self._idle.get()
            loop = asyncio.get_running_loop()
            if deadline is not None:
                timeout = min(timeout, deadline - loop.time())
                if timeout <= 0:
                    self._idle.put_nowait(worker)
                    raise TaskTimeout(0.0)
            fut = loop.run_in_executor(self._threads, self._call_and_release, loop, worker, fn, payload, timeout)
            return unwrap(await asyncio.shield(fut))
        finally:
            self._pending -= 1

    def _call_and_release(self, loop: asyncio.AbstractEventLoop, worker: _Worker, fn: TaskFn, payload: Payload,
                          timeout: float) -> Outcome:
        try:
            return worker.call(fn, payload, timeout)
        finally:
            if not loop.is_closed():
                loop.call_soon_threadsafe(self._idle.put_nowait, worker)

    def pids(self) -> list[int]:
        return [w.proc.pid for w in self._workers]

    def close(self) -> None:
        for w in self._workers:
            w.stop()
        self._threads.shutdown(wait=False, cancel_futures=True)


class Runner(Protocol):
    """Where batch items run: the local :class:`WorkerPool` or a :class:`DaskRunner`."""

    async def run(self, fn: TaskFn, payload: Payload, timeout: float, *, wait: bool = False,
                  deadline: float | None = None) -> Payload: ...


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
                  deadline: float | None = None) -> Payload:
        fut = self._client.submit(execute, fn, payload, pure=False)
        try:
            outcome = await asyncio.wait_for(fut, timeout)
        except TimeoutError:
            await self._client.cancel(fut)
            raise TaskTimeout(timeout) from None
        return unwrap(outcome)

    async def close(self) -> None:
        await self._client.close()
