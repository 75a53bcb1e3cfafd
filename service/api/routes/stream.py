"""Live streaming shaper: ``WS /v1/stream`` (the API key, when the server has one, is checked here), and
``GET /v1/stream/example``: the paper's interaction example to play through it (the page's Stream tab).

Protocol (JSON text frames)::

    client -> {"params": "paper-rig" | {J, B, ...}, "current": 1.0, "voltage": 12.0,
               "regularity": "continuous-voltage", "delay": 0.1, "dt": 0.001, "bandwidth": 20,
               "api_key": "..."}                                   # first frame: the session
    server -> {"type": "ready", "preview": 100, "delay": 0.1, "dt": 0.001, "max_samples": ..., "pid": ...}
    client -> {"t": [...], "thrust": [...]}                        # 1..MAX_BATCH samples per frame
    server -> {"type": "samples", "t": [...], "desired": [...], "thrust": [...], "omega": [...],
               "current": [...], "voltage": [...], "saturated": [...]}
    server -> {"type": "error", "field": ..., "reason": ...}       # then the socket closes (1008 / 1007 / 1011)

Browsers cannot set headers on a WebSocket, so the key may come as ``Authorization: Bearer`` or as the
first frame's ``api_key``. ``params`` is a preset name or a mapping: never a path (the server reads no
file a client names).

Bounds, all checked before the work they guard: sessions per server (:data:`MAX_SESSIONS`), samples
per session (:data:`MAX_SAMPLES`), samples per frame (:data:`MAX_BATCH`), sample rate (a token bucket
of :data:`MAX_RATE` samples/s with a burst of :data:`MAX_BURST`), an idle timeout and the frame size.

No shaping runs in the server process. Each live session gets its own spawned child process
(:class:`service.streams.StreamSession`) that builds and keeps the session's :class:`~ocp.stream.StreamShaper`;
the server parses and bounds each frame, then forwards it over a pipe (waited on in the session's own thread,
so the event loop keeps serving). The session cap therefore also caps these processes. A frame has a hard
timeout (:data:`FRAME_TIMEOUT_S`): past it the child is killed and the socket closes with 1011 and the reason;
a child that dies is reported the same way and never takes the server down. The child is killed on
disconnect, idle timeout and every refusal. ``GET /v1/stream/example`` runs as a task in the worker pool
(:func:`service.streams.stream_example`, cached per worker).
"""

from __future__ import annotations

import asyncio
import contextlib
import hmac
import time
from enum import IntEnum
from typing import Annotated, Any

from fastapi import APIRouter, Depends, Query, WebSocket, WebSocketDisconnect
from pydantic import BaseModel, ConfigDict, Field, ValidationError

from ocp.errors import ThrustshapeError, validation_location
from ocp.gallery.interaction import Law
from ocp.theory.reversal import ReversalRegularity
from service.api.deps import PoolDep, SettingsDep, require_api_key
from service.streams import EXAMPLE_MAX_DURATION_S, StreamSession, stream_example
from service.workers import TaskFailed, TaskTimeout

MAX_SESSIONS = 4
MAX_SAMPLES = 600_000  # per session: 10 min at 1 kHz
MAX_BATCH = 200  # samples per frame
MAX_RATE = 5_000.0  # samples/s, sustained
MAX_BURST = 2_000  # samples
IDLE_S = 30.0
MAX_FRAME_CHARS = 64 * 1024
OPEN_TIMEOUT_S = 60.0  # the session's process: spawn, imports, the shaper's design
FRAME_TIMEOUT_S = 10.0  # hard, per frame (a frame of MAX_BATCH samples takes a few ms)

router = APIRouter(tags=["stream"])


class ExampleRate(IntEnum):
    """Sample rates of the example [Hz] (an enum: a ``Literal`` of ints refuses the query string "500")."""

    HZ_500 = 500
    HZ_1000 = 1000


class StreamExample(BaseModel):
    """The paper's Section IV-B reference sampled for streaming: ``t`` [s], ``thrust`` [N]."""

    law: Law
    rate: float
    amplitude: float
    t: list[float]
    thrust: list[float]
    crossings: list[float]  # sample times just before each sign change [s]


@router.get("/v1/stream/example", response_model=StreamExample, dependencies=[Depends(require_api_key)],
            summary="The paper's interaction example (impedance/admittance) as a thrust reference to stream")
async def example(settings: SettingsDep, pool: PoolDep, law: Law = Law.IMPEDANCE,
                  duration: Annotated[float, Query(ge=0.5, le=EXAMPLE_MAX_DURATION_S)] = 10.0,
                  rate: ExampleRate = ExampleRate.HZ_1000,
                  amplitude: Annotated[float, Query(gt=0, le=100)] = 0.4) -> Any:
    """The first ``duration`` seconds of Section IV-B's reference, thrust peak ``amplitude`` [N]. A fixed
    example: ~2 s of ODE integration in a worker the first time per (law, rate), cached in that worker."""
    payload = {"law": law.value, "duration": duration, "rate": float(rate), "amplitude": amplitude}
    return await pool.run(stream_example, payload, settings.task_timeout_s)


class StreamStart(BaseModel):
    """First frame of a session (units: A, V, s, Hz; see :class:`ocp.stream.StreamOptions`)."""

    model_config = ConfigDict(extra="forbid")

    params: str | dict[str, Any]
    current: float
    voltage: float
    regularity: ReversalRegularity = ReversalRegularity.CONTINUOUS_VOLTAGE
    delay: float = 0.1
    dt: float = 0.001
    bandwidth: float = 20.0
    api_key: str | None = None


class StreamBatch(BaseModel):
    """A frame of samples: times [s] and desired thrust [N], equal lengths."""

    model_config = ConfigDict(extra="forbid")

    t: list[float] = Field(min_length=1, max_length=MAX_BATCH)
    thrust: list[float] = Field(min_length=1, max_length=MAX_BATCH)


class _Refused(Exception):
    def __init__(self, field: str, reason: str, code: int = 1008) -> None:
        self.field, self.reason, self.code = field, reason, code


def _parse(model: type[BaseModel], text: str) -> Any:
    if len(text) > MAX_FRAME_CHARS:
        raise _Refused("frame", f"{len(text)} characters; at most {MAX_FRAME_CHARS}", 1009)
    try:
        return model.model_validate_json(text)
    except ValidationError as exc:
        field, reason = validation_location(exc.errors()[0])
        raise _Refused(field or "frame", reason, 1007) from None


def _key_ok(ws: WebSocket, start: StreamStart) -> bool:
    settings = ws.app.state.settings
    if settings.api_key is None:
        return True
    key = settings.api_key.get_secret_value().encode()
    header = ws.headers.get("authorization", "")
    given = header[7:] if header.lower().startswith("bearer ") else (start.api_key or "")
    return hmac.compare_digest(given.encode(), key)


class _Bucket:
    """Token bucket: ``MAX_RATE`` samples/s sustained, ``MAX_BURST`` at once."""

    def __init__(self) -> None:
        self.tokens, self.last = float(MAX_BURST), time.monotonic()

    def take(self, n: int) -> None:
        now = time.monotonic()
        self.tokens = min(float(MAX_BURST), self.tokens + (now - self.last) * MAX_RATE)
        self.last = now
        if n > self.tokens:
            raise _Refused("rate", f"more than {MAX_RATE:g} samples/s (burst {MAX_BURST})")
        self.tokens -= n


async def _receive(ws: WebSocket) -> str:
    """The next text frame (idle timeout); a binary frame is refused."""
    msg = await asyncio.wait_for(ws.receive(), IDLE_S)
    if msg["type"] == "websocket.disconnect":
        raise WebSocketDisconnect(msg.get("code", 1000))
    text = msg.get("text")
    if text is None:
        raise _Refused("frame", "frames are JSON text, not binary", 1003)
    return str(text)


async def _session(ws: WebSocket, session: StreamSession) -> None:
    start = _parse(StreamStart, await _receive(ws))
    if not _key_ok(ws, start):
        raise _Refused("api_key", "missing or wrong API key (Authorization: Bearer or the first frame's api_key)")
    try:
        ready = await session.open(start.model_dump(mode="json", exclude={"api_key"}), OPEN_TIMEOUT_S)
    except ThrustshapeError as exc:
        raise _Refused(exc.field, exc.reason, 1007) from None
    await ws.send_json({**ready, "max_samples": MAX_SAMPLES, "max_batch": MAX_BATCH, "max_rate": MAX_RATE})
    bucket, total = _Bucket(), 0
    while True:
        batch = _parse(StreamBatch, await _receive(ws))
        if len(batch.t) != len(batch.thrust):
            raise _Refused("thrust", f"{len(batch.thrust)} values for {len(batch.t)} times", 1007)
        total += len(batch.t)
        if total > MAX_SAMPLES:
            raise _Refused("t", f"a session carries at most {MAX_SAMPLES} samples")
        bucket.take(len(batch.t))
        try:
            text = await session.push(batch.model_dump(), FRAME_TIMEOUT_S)
        except ThrustshapeError as exc:
            raise _Refused(exc.field, exc.reason, 1007) from None
        await ws.send_text(text)


@router.websocket("/v1/stream")
async def stream(ws: WebSocket) -> None:
    """One live stream per connection (module doc)."""
    state = ws.app.state
    await ws.accept()
    active = getattr(state, "stream_sessions", 0)
    if active >= MAX_SESSIONS:
        await ws.send_json({"type": "error", "field": "session", "reason": f"at most {MAX_SESSIONS} live streams"})
        await ws.close(1013)
        return
    state.stream_sessions = active + 1
    refusal: tuple[str, str, int] | None = None
    session = StreamSession()
    try:
        await _session(ws, session)
    except _Refused as exc:
        refusal = (exc.field, exc.reason, exc.code)
    except TaskTimeout as exc:  # the shaper overran: its process was killed
        refusal = ("session", f"the session's process did not answer within {exc.timeout:g} s and was stopped", 1011)
    except TaskFailed as exc:
        refusal = ("session", exc.detail, 1011)
    except TimeoutError:
        refusal = ("session", f"idle for {IDLE_S:g} s", 1001)
    except WebSocketDisconnect:
        pass
    finally:
        # the slot (and the process) is free once the work is over, not after the closing handshake
        # (a slow client must not hold it)
        session.close()
        state.stream_sessions -= 1
    if refusal is not None:
        await _goodbye(ws, *refusal)


async def _goodbye(ws: WebSocket, field: str, reason: str, code: int) -> None:
    """Tell the client why, then close; a client that already left is not an error."""
    with contextlib.suppress(WebSocketDisconnect, RuntimeError, OSError):
        await ws.send_json({"type": "error", "field": field, "reason": reason})
        await ws.close(code)

