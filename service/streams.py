"""Stream sessions in their own processes: one spawned child per live ``WS /v1/stream`` session.

The shaper is stateful (its look-ahead buffer, governor and tracker states carry from one sample to the
next), so a session cannot hop between the pool's workers; instead each session gets a dedicated child
process (``spawn``, like :mod:`service.workers`) that builds the :class:`~ocp.stream.StreamShaper` and
keeps it. The server only parses, bounds and forwards frames over a :func:`multiprocessing.Pipe`.

Every answer crosses the pipe as a :data:`service.workers.Outcome` (``execute``/``unwrap``): a
:class:`~ocp.errors.ThrustshapeError` with its ``field`` and ``reason`` comes back as data; anything
else, or a child that died, becomes :class:`~service.workers.TaskFailed`; a frame that overruns its hard
timeout kills the child (:class:`~service.workers.TaskTimeout`). The blocking wait on the pipe runs in the
session's own single thread, which only waits: the event loop keeps serving.

:func:`stream_example` is a pool task (the Stream tab's example reference), cached per worker.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import multiprocessing as mp
import os
import signal
import time
from concurrent.futures import ThreadPoolExecutor
from functools import lru_cache, partial
from multiprocessing.connection import Connection
from typing import Any

from service.workers import Outcome, Payload, TaskFailed, TaskTimeout, execute, unwrap

COLUMNS = ("t", "desired", "thrust", "omega", "current", "voltage", "saturated")
EXAMPLE_MAX_DURATION_S = 10.0


def _open(start: Payload) -> tuple[Any, Payload]:
    """``start`` (the session's first frame, validated by the route) -> the shaper and the ready frame."""
    from ocp.errors import MissionError
    from ocp.model.params import PRESETS, load_params
    from ocp.stream import StreamShaper, stream_options

    opts = stream_options(current=start["current"], voltage=start["voltage"], regularity=start["regularity"],
                          delay=start["delay"], dt=start["dt"], bandwidth=start["bandwidth"])
    if isinstance(start["params"], str) and start["params"] not in PRESETS:
        raise MissionError("params", f"a preset name {list(PRESETS)} or a mapping of parameters")
    shaper = StreamShaper(load_params(start["params"]), opts)
    return shaper, {"type": "ready", "preview": opts.preview, "delay": opts.delay, "dt": opts.dt,
                    "regularity": opts.regularity.value, "current": opts.current, "voltage": opts.voltage,
                    "pid": os.getpid()}


def _push(shaper: Any, frame: Payload) -> Payload:
    """Push a frame ``{"t": [...] s, "thrust": [...] N}`` through the shaper; the output as a JSON text."""
    rows = [shaper.push(a, b) for a, b in zip(frame["t"], frame["thrust"], strict=True)]
    out: dict[str, Any] = {"type": "samples"}
    for name in COLUMNS:
        out[name] = [getattr(r, name) for r in rows]
    return {"text": json.dumps(out, allow_nan=False)}


def _session_main(conn: Connection, start: Payload) -> None:
    """The child: build the shaper, answer ready (or the error), then one outcome per frame until EOF."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # the server decides when sessions end
    box: list[Any] = []

    def opened(payload: Payload) -> Payload:
        shaper, ready = _open(payload)
        box.append(shaper)
        return ready

    outcome = execute(opened, start)
    conn.send(outcome)
    if outcome[0] != "ok":
        return
    while True:
        try:
            frame = conn.recv()
        except (EOFError, OSError):
            return
        if frame is None:
            return
        conn.send(execute(partial(_push, box[0]), frame))


class StreamSession:
    """The server's handle on one session's child process; one coroutine uses it at a time.

    ``await open(start, timeout)`` -> the ready frame; ``await push(frame, timeout)`` -> the samples frame
    as JSON text; :meth:`close` kills the child (always call it: disconnect, idle, refusal, error).
    """

    def __init__(self) -> None:
        self._conn: Connection | None = None
        self._proc: Any = None
        self._waiter = ThreadPoolExecutor(max_workers=1, thread_name_prefix="thrustshape-stream-wait")

    @property
    def pid(self) -> int | None:
        return None if self._proc is None else self._proc.pid

    async def open(self, start: Payload, timeout: float) -> Payload:
        """Start the child with the session's first frame; the ready frame, or the shaper's error raised."""
        ctx = mp.get_context("spawn")
        self._conn, child = ctx.Pipe()
        self._proc = ctx.Process(target=_session_main, args=(child, start), daemon=True, name="thrustshape-stream")
        try:
            self._proc.start()
        except OSError as exc:  # no process to be had (limits): the session is refused, the server goes on
            self._proc = None
            raise TaskFailed(f"could not start the session's process: {exc}") from None
        finally:
            child.close()
        return await self._answer(timeout)

    async def push(self, frame: Payload, timeout: float) -> str:
        """One frame through the child's shaper (hard ``timeout`` [s]); the samples frame as JSON text."""
        assert self._conn is not None, "open() first"
        try:
            self._conn.send(frame)
        except (OSError, BrokenPipeError):
            detail = await asyncio.get_running_loop().run_in_executor(self._waiter, self._died)
            raise TaskFailed(detail) from None
        return str((await self._answer(timeout))["text"])

    async def _answer(self, timeout: float) -> Payload:
        loop = asyncio.get_running_loop()
        # the timeout counts from now, not from when the waiting thread gets to run
        outcome = await loop.run_in_executor(self._waiter, self._wait, time.monotonic() + timeout)
        if outcome is None:
            self.close()
            raise TaskTimeout(timeout)
        return unwrap(outcome)

    def _wait(self, deadline: float) -> Outcome | None:
        """Blocking, in the session's thread: the child's next outcome, ``None`` when it was not there by
        ``deadline`` (``time.monotonic()`` [s])."""
        assert self._conn is not None
        try:
            if not self._conn.poll(max(deadline - time.monotonic(), 0.0)) or time.monotonic() > deadline:
                return None
            return self._conn.recv()
        except (EOFError, OSError):
            return "crash", self._died()

    def _died(self) -> str:
        self._proc.join(1.0)
        return f"the session's process ended unexpectedly (exit code {self._proc.exitcode})"

    def close(self) -> None:
        """Kill the child (if it runs), free the pipe, reap the child in the session's thread (the event loop
        never waits on it); idempotent."""
        if self._proc is not None and self._proc.is_alive():
            self._proc.kill()
        if self._conn is not None:
            self._conn.close()
        if self._proc is not None:
            with contextlib.suppress(RuntimeError):  # already shut down: reaped by an earlier close
                self._waiter.submit(self._proc.join, 5.0)
        self._waiter.shutdown(wait=False)


@lru_cache(maxsize=4)
def _example_full(law: str, rate: float) -> tuple[Any, Any]:
    """Section IV-B's impedance or admittance reference (M_I = 0.65, B_I = 3.5, K_I = 5.0, ...) over the
    longest example, normalised: (t, x2d). At most four of these exist per worker (two laws, two rates)."""
    from ocp.gallery.interaction import InteractionSetup, Law, interaction_reference

    ref = interaction_reference(Law(law), InteractionSetup(duration=EXAMPLE_MAX_DURATION_S), rate=rate)
    return ref.t, ref.x2d


def stream_example(payload: Payload) -> Payload:
    """Pool task: ``{"law", "duration" [s], "rate" [Hz], "amplitude" [N]}`` -> the first ``duration`` seconds of
    the example (the paper's normalised time read as seconds), thrust scaled to a peak of ``amplitude`` (the
    paper's example is normalised; a rig needs newtons), and the sample times just before each sign change."""
    import numpy as np

    rate = float(payload["rate"])
    t, x2d = _example_full(str(payload["law"]), rate)
    n = round(float(payload["duration"]) * rate) + 1
    t, x2d = t[:n], x2d[:n]
    scale = float(payload["amplitude"]) / float(np.max(np.abs(x2d)))
    crossings = t[:-1][x2d[:-1] * x2d[1:] < 0]
    return {"law": payload["law"], "rate": rate, "amplitude": payload["amplitude"], "t": t.tolist(),
            "thrust": (x2d * scale).tolist(), "crossings": crossings.tolist()}
