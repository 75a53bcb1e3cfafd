"""Worker processes for CPU-bound solves, and the Dask alternative for batch items.

:class:`WorkerPool` owns ``n`` long-lived processes (spawned, so each has its own solver cache and
nothing is shared with the server's threads). A task is any importable top-level function
``fn(payload: dict) -> dict``; it travels by reference over a pipe. Each call has a hard wall-clock
timeout: when it expires the process is killed and replaced, so a runaway solve costs one process,
never the server. A task may report an expensive one-off build (:func:`report_phase`): a deadline that runs
out during it is answered at once, but the process finishes the build (up to the pool's ``build_limit``) and
keeps it. Calls beyond ``workers + queue_size`` are refused at once with :class:`QueueFull` (the API answers
503 + Retry-After). Which free worker takes which waiting call is decided by :class:`service.dispatch.Dispatcher`:
calls with a deadline first, then a call's *affinity* (e.g. its solver structure) to the worker that already
built it; each worker counts the builds its tasks report (:meth:`WorkerPool.builds`).

Errors cross the process boundary as data, not as pickled exceptions: a
:class:`~ocp.errors.ThrustshapeError` raised by a task comes back as the same class with its
``field`` and ``reason``; anything else becomes :class:`TaskFailed`.

:class:`service.dask_runner.DaskRunner` runs the same task functions on a ``distributed`` cluster (batch
items only).
"""

from __future__ import annotations

import asyncio
import contextlib
import contextvars
import importlib
import logging
import multiprocessing as mp
import os
import signal
import time
from collections.abc import Callable, Hashable, Sequence
from concurrent.futures import ThreadPoolExecutor
from multiprocessing.connection import Connection
from typing import Any, Literal, Protocol, cast

import ocp.errors as errors
from service import limits
from service.dispatch import Dispatcher
from service.errors import QueueFull, TaskFailed, TaskTimeout

Payload = dict[str, Any]
TaskFn = Callable[[Payload], Payload]
Outcome = tuple[Literal["ok", "user-error", "crash"], Any]
Phase = Literal["queue", "start-up", "build", "run"]

_STARTUP_TIMEOUT_S = 120.0
_WARM_UP_TIMEOUT_S = 30.0
_ABORT_GRACE_S = 5.0  # an abandoned task, told to stop after its build, must answer within this [s]
#: what a task was waiting for when its deadline ran out
PHASES: dict[str, str] = TaskTimeout.PHASES
log = logging.getLogger("thrustshape.workers")
_REPLACED = object()  # a released worker whose process was replaced: it holds nothing
_PARENT: list[Connection] = []  # inside a worker process: its end of the pipe (empty elsewhere)
_UNTIL: list[float] = []  # inside a worker process: monotonic time at which the current call is killed


def time_left() -> float | None:
    """Inside a worker: seconds before the current call's process is killed (a task can stop its own work
    before that, and keep the process and its caches); ``None`` outside a worker."""
    return _UNTIL[0] - time.monotonic() if _UNTIL else None


class TaskAbandoned(Exception):
    """Raised inside a worker by :func:`report_phase` ``("built")`` when the caller stopped waiting during the
    build: the build is kept (cached by the task), the rest of the task is skipped."""


def report_phase(stage: str) -> None:
    """Called by a task inside a worker around an expensive one-off build (e.g. a solver it caches):
    ``"build"`` before, ``"built"`` once the result is cached. A caller whose deadline runs out during the
    build is answered at once, but the process is not killed: it finishes the build (up to the pool's
    ``build_limit``) and, at ``"built"``, is told to stop (:class:`TaskAbandoned`) or go on. No-op outside a
    worker process."""
    if not _PARENT:
        return
    _PARENT[0].send(("phase", stage))
    if stage == "built" and _PARENT[0].recv() != "go":
        raise TaskAbandoned("the caller's deadline ran out during the build; the build is kept")


def execute(fn: TaskFn, payload: Payload) -> Outcome:
    """Run ``fn(payload)`` and turn every exception into data (runs inside a worker). Memory refused under the
    worker's cap (:func:`service.limits.cap_memory`) is the request's fault: a user error naming the cap."""
    try:
        return "ok", fn(payload)
    except errors.ThrustshapeError as exc:
        return "user-error", (type(exc).__name__, exc.field, exc.reason)
    except MemoryError:
        return "user-error", ("ThrustshapeError", "request", limits.over_memory())
    except Exception as exc:  # a worker must answer, whatever the task did
        return "crash", f"{type(exc).__name__}: {exc}"


def unwrap(outcome: Outcome) -> Payload:
    """The task's result, or the exception it stands for (a ThrustshapeError leaf or TaskFailed)."""
    kind, value = outcome
    if kind == "ok":
        return value
    if kind == "user-error":
        raise user_error(*value)
    raise TaskFailed(str(value))


def user_error(name: str, field: str, reason: str) -> errors.ThrustshapeError:
    """The core error a worker reported as data (its class by name, a plain ThrustshapeError if unknown)."""
    cls = getattr(errors, name, errors.ThrustshapeError)
    if not (isinstance(cls, type) and issubclass(cls, errors.ThrustshapeError)):
        cls = errors.ThrustshapeError
    return cls(field, reason)


def _worker_main(conn: Connection, preload: Sequence[str], niceness: int = 0, memory_mib: int | None = None) -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the server decides when workers stop
    limits.first_to_go_when_memory_runs_out()
    if memory_mib:
        limits.cap_memory(memory_mib)
    if niceness:
        with contextlib.suppress(OSError):
            os.nice(niceness)
    for name in preload:
        with contextlib.suppress(ImportError):
            importlib.import_module(name)
    _PARENT.append(conn)
    conn.send(("ready", None))
    while True:
        try:
            msg = conn.recv()
        except (EOFError, OSError):
            return
        if msg is None:
            return
        if not isinstance(msg, tuple):  # a reply to a build report that came after its task ended
            continue
        fn, payload, budget = msg
        _UNTIL[:] = [time.monotonic() + budget]
        conn.send(execute(fn, payload))


class _Worker:
    """One solver process and the parent's end of its pipe; used by one thread at a time."""

    def __init__(self, ctx: Any, preload: Sequence[str], niceness: int = 0, memory_mib: int | None = None) -> None:
        self._ctx, self._preload, self._niceness, self._memory_mib = ctx, tuple(preload), niceness, memory_mib
        self._ready = False
        self.builds = 0  # solver builds this worker reported (its processes' lifetimes added up)
        self.conn: Connection
        self.proc: Any
        self._spawn()

    def _spawn(self) -> None:
        parent, child = self._ctx.Pipe()
        self.proc = self._ctx.Process(target=_worker_main,
                                      args=(child, self._preload, self._niceness, self._memory_mib),
                                      daemon=True,
                                      name="thrustshape-worker")
        self.proc.start()
        child.close()
        self.conn, self._ready = parent, False

    @property
    def ready(self) -> bool:
        return self._ready

    def _await_ready(self, timeout: float = _STARTUP_TIMEOUT_S) -> None:
        """Wait up to ``timeout`` [s] for a (re)spawned process; a process that is merely slow keeps starting
        (:class:`TaskTimeout` ``start-up``), one that died or never starts is replaced."""
        if self._ready:
            return
        if not self.conn.poll(min(timeout, _STARTUP_TIMEOUT_S)):
            if timeout < _STARTUP_TIMEOUT_S and self.proc.is_alive():
                raise TaskTimeout(timeout, "start-up")
            log.error("worker %s did not start within %g s; respawning", self.proc.pid, _STARTUP_TIMEOUT_S)
            self.restart()
            raise TaskFailed("worker process did not start", startup=True)
        try:
            self.conn.recv()
        except (EOFError, OSError):
            log.error("worker %s died while starting (exit code %s); respawning", self.proc.pid, self.proc.exitcode)
            self.restart()
            raise TaskFailed("worker process died while starting", startup=True) from None
        self._ready = True

    def call(self, fn: TaskFn, payload: Payload, timeout: float,
             on_overrun: Callable[[TaskTimeout], None] | None = None, build_limit: float = 0.0) -> Outcome:
        """Blocking: run one task within ``timeout`` [s] (start-up of a respawned process included); kill +
        respawn the process on timeout or death. With ``on_overrun`` and ``build_limit`` [s], a deadline that
        runs out while the task reports a build (:func:`report_phase`) calls ``on_overrun`` (the caller is
        answered elsewhere) and the process finishes the build, up to ``build_limit`` after it began, then
        is told to stop; only a build past that limit is killed."""
        start = time.monotonic()
        self._await_ready(timeout)
        budget = timeout - (time.monotonic() - start)
        if budget <= 0:
            raise TaskTimeout(timeout, "start-up")
        name = getattr(fn, "__name__", fn)
        try:
            self.conn.send((fn, payload, budget))
            return self._follow(name, timeout, time.monotonic() + budget, on_overrun, build_limit)
        except (EOFError, OSError, BrokenPipeError):
            code = self.proc.exitcode
            log.error("worker %s died during %s (exit code %s); respawning", self.proc.pid, name, code)
            self.restart()
            raise TaskFailed(f"worker process died (exit code {code})") from None

    def _follow(self, name: object, timeout: float, end: float, on_overrun: Callable[[TaskTimeout], None] | None,
                build_limit: float) -> Outcome:
        """Read the task's phase reports until its outcome; kill at ``end`` unless a build is being kept."""
        build_start: float | None = None
        abandoned = False
        while True:
            if not self.conn.poll(max(end - time.monotonic(), 0.0)):
                phase: Phase = "build" if build_start is not None else "run"
                if build_start is not None and not abandoned and on_overrun is not None and build_limit > 0:
                    abandoned, end = True, build_start + build_limit
                    log.warning("worker %s: %s ran out of time while building; answered elsewhere, the worker "
                                "finishes the build (limit %.3g s)", self.proc.pid, name, build_limit)
                    on_overrun(TaskTimeout(timeout, "build"))
                    continue
                log.warning("worker %s: %s exceeded its %s; killing and respawning", self.proc.pid, name,
                            f"{build_limit:.3g} s build limit" if abandoned else f"{timeout:.3g} s deadline ({phase})")
                self.restart()
                raise TaskTimeout(timeout, phase)
            msg = self.conn.recv()
            if msg[0] != "phase":
                return cast(Outcome, msg)
            if msg[1] == "build":
                build_start = time.monotonic()
                self.builds += 1
                continue
            log.info("worker %s: %s built its solver in %.3g s", self.proc.pid, name,
                     time.monotonic() - (build_start or time.monotonic()))
            build_start = None
            self.conn.send("abort" if abandoned else "go")
            if abandoned:
                end = time.monotonic() + _ABORT_GRACE_S

    def restart(self) -> None:
        old = self.proc.pid
        self.kill()
        self._spawn()
        log.info("worker %s replaced by %s", old, self.proc.pid)

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
                 preload: Sequence[str] = ("ocp.reference.analytic", "ocp.reference.fallback", "ocp.optimize.mission"),
                 build_limit: float = 0.0, niceness: int = 0, affinity_slots: int = 8,
                 memory_mib: int | None = None) -> None:
        """``build_limit`` [s]: how long a worker whose caller's deadline ran out during a reported build
        (:func:`report_phase`) may go on building before it is killed (0: killed at the deadline).
        ``niceness``: added to the processes' nice value (a pool of long solves yields the CPU to a pool of
        short, deadline-bound fallbacks). ``affinity_slots``: affinity keys remembered per worker (as many as
        a worker process caches programs, :data:`ocp.optimize.collocation.CACHE_SIZE`). ``memory_mib``: each
        process's data memory cap (:func:`service.limits.cap_memory`; None: none)."""
        self.size = workers
        self.build_limit = build_limit
        self.capacity = workers + queue_size
        self.retry_after = retry_after
        self._ctx = mp.get_context("spawn")
        self._workers = [_Worker(self._ctx, preload, niceness, memory_mib) for _ in range(workers)]
        self._threads = ThreadPoolExecutor(max_workers=workers, thread_name_prefix="thrustshape-call")
        self._dispatch: Dispatcher[_Worker] = Dispatcher(self._workers, slots=affinity_slots)
        self._pending = 0
        self._background = 0  # background calls (``wait=True``) waiting for a worker: not counted against capacity
        self._warm_up: tuple[TaskFn, Payload] | None = None  # what a (re)started process runs before its first call

    @property
    def pending(self) -> int:
        """Calls admitted and not finished (running + waiting)."""
        return self._pending

    async def run(self, fn: TaskFn, payload: Payload, timeout: float, *, wait: bool = False,
                  deadline: float | None = None, min_run: float = 0.0, affinity: Hashable | None = None) -> Payload:
        """Run ``fn(payload)`` in a worker with a hard ``timeout`` [s].

        ``wait=True`` (a background call, e.g. a batch item) waits for a free worker, behind every call with a
        deadline, instead of raising :class:`QueueFull`; while waiting it does not count against the capacity.
        ``deadline`` (event loop time; default ``timeout`` from now unless ``wait``) also counts the wait for a
        worker and the start-up of a respawned one: the task gets what is left of it. When less than ``min_run``
        [s] is left once a worker is free, the task is not started (:class:`TaskTimeout` ``queue``): starting it
        would only get its process killed and respawned, which costs the next calls a start-up. ``affinity``:
        what the call leaves built in its worker (e.g. a solver structure); a worker that holds it is preferred
        (:class:`service.dispatch.Dispatcher`).
        """
        if not wait and self._pending - self._background >= self.capacity:
            raise QueueFull(self.retry_after)
        self._pending += 1
        loop = asyncio.get_running_loop()
        try:
            if wait:
                worker = await self._background_get(affinity)
            else:
                deadline = loop.time() + timeout if deadline is None else deadline
                try:
                    worker = await asyncio.wait_for(self._dispatch.get(affinity, urgent=True),
                                                    max(deadline - loop.time(), 0.0))
                except TimeoutError:
                    log.warning("%s: deadline ran out after waiting %.3g s for a free worker",
                                getattr(fn, "__name__", fn), timeout)
                    raise TaskTimeout(timeout, "queue") from None
                timeout = deadline - loop.time()
                if timeout <= max(min_run, 0.0):
                    self._dispatch.put(worker)
                    raise TaskTimeout(max(timeout, 0.0), "queue")
            # the call's thread runs in this request's context: its kill/respawn lines carry the request id;
            # ``answer`` may be settled before the thread ends (a deadline during a build that the worker finishes)
            answer: asyncio.Future[Outcome] = loop.create_future()
            loop.run_in_executor(self._threads, contextvars.copy_context().run, self._call_and_release, loop,
                                 worker, fn, payload, timeout, answer, affinity)
            return unwrap(await answer)
        finally:
            self._pending -= 1

    async def _background_get(self, affinity: Hashable | None) -> _Worker:
        self._background += 1
        try:
            return await self._dispatch.get(affinity)
        finally:
            self._background -= 1

    def _call_and_release(self, loop: asyncio.AbstractEventLoop, worker: _Worker, fn: TaskFn, payload: Payload,
                          timeout: float, answer: asyncio.Future[Outcome], affinity: Hashable | None) -> None:
        def settle(outcome: Outcome | None, exc: BaseException | None) -> None:
            if not loop.is_closed():
                loop.call_soon_threadsafe(_settle, answer, outcome, exc)

        pid = worker.proc.pid
        try:
            settle(worker.call(fn, payload, timeout, lambda exc: settle(None, exc), self.build_limit), None)
        except BaseException as exc:  # handed to the awaiting request (a TaskTimeout, TaskFailed, ...)
            settle(None, exc)
        finally:
            # a respawned process re-enters the pool once started (and warmed up, as at the pool's start): no
            # request waits for a start-up or a first-call cost it could skip
            with contextlib.suppress(TaskFailed, TaskTimeout, OSError, EOFError):
                worker._await_ready()
                if worker.proc.pid != pid and self._warm_up is not None:
                    self._run_warm_up(worker)
            if not loop.is_closed():
                loop.call_soon_threadsafe(self._release, worker, affinity if worker.proc.pid == pid else _REPLACED)

    def _release(self, worker: _Worker, held: Hashable | None) -> None:
        """Back in the pool (event loop): it now holds ``held``, or nothing if its process was replaced."""
        if held is _REPLACED:
            self._dispatch.forget(worker)
        else:
            self._dispatch.remember(worker, held)
        self._dispatch.put(worker)

    async def warm(self, task: TaskFn | None = None, payload: Payload | None = None) -> None:
        """Wait for every process to finish starting (one at a time, each taken off the idle queue meanwhile,
        so a request never shares a worker with its start-up); with ``task``, run it once on each with
        ``payload`` so its first real call finds its imports and caches ready, and again on every process that
        replaces one (killed after a timeout, or dead) before it takes a call."""
        loop = asyncio.get_running_loop()
        if task is not None:
            self._warm_up = (task, payload or {})
        for _ in range(self.size):
            worker = await self._dispatch.get(urgent=True)
            try:
                await loop.run_in_executor(self._threads, worker._await_ready)
                if task is not None:
                    await loop.run_in_executor(self._threads, self._run_warm_up, worker)
            except (TaskFailed, TaskTimeout) as exc:
                log.error("worker did not start: %s", exc)
            finally:
                self._dispatch.put(worker)

    def _run_warm_up(self, worker: _Worker) -> None:
        """The pool's warm-up task on ``worker`` (blocking; its outcome is dropped, a timeout kills the process
        like any call's)."""
        if self._warm_up is not None:
            fn, payload = self._warm_up
            outcome = worker.call(fn, payload, _WARM_UP_TIMEOUT_S)
            if outcome[0] != "ok":
                log.warning("worker %s: warm-up %s answered %s", worker.proc.pid, getattr(fn, "__name__", fn),
                            outcome[0])
            else:
                log.info("worker %s warmed up", worker.proc.pid)

    def ready(self) -> int:
        """Worker processes that finished starting (imports done, answering)."""
        return sum(1 for w in self._workers if w.ready)

    def builds(self) -> list[int]:
        """Solver builds each worker reported (:func:`report_phase`), in worker order."""
        return [w.builds for w in self._workers]

    def pids(self) -> list[int]:
        return [w.proc.pid for w in self._workers]

    def alive(self) -> int:
        """Worker processes currently alive (a killed one counts until it is replaced)."""
        return sum(1 for w in self._workers if w.proc.is_alive())

    def close(self) -> None:
        for w in self._workers:
            w.stop()
        self._threads.shutdown(wait=False, cancel_futures=True)


def _settle(answer: asyncio.Future[Outcome], outcome: Outcome | None, exc: BaseException | None) -> None:
    """Resolve a call's answer once (later outcomes of an abandoned call are dropped)."""
    if answer.done():
        return
    if exc is not None:
        answer.set_exception(exc)
    else:
        answer.set_result(cast(Outcome, outcome))


class Runner(Protocol):
    """Where batch items run: the local :class:`WorkerPool` or a :class:`~service.dask_runner.DaskRunner`."""

    async def run(self, fn: TaskFn, payload: Payload, timeout: float, *, wait: bool = False,
                  deadline: float | None = None, affinity: Hashable | None = None) -> Payload: ...
