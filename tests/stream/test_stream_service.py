"""``WS /v1/stream`` on a real uvicorn server with an API key: the answers are the core shaper's, and every
bound (key, frame, rate, sessions, bad samples, file paths) is enforced with the field and the reason."""

from __future__ import annotations

import asyncio
import contextlib
import json
import re
import time
from collections.abc import Iterator
from typing import Any

import httpx
import numpy as np
import pytest

from ocp.errors import ThrustshapeError
from ocp.gallery.interaction import Law, interaction_reference
from ocp.model.params import MotorParams
from ocp.stream import shape_profile, stream_options
from service.api.routes.stream import MAX_BATCH, MAX_SESSIONS
from service.streams import StreamSession
from service.workers import TaskTimeout
from tests.service.test_service_support import Server, start_server

ws_client = pytest.importorskip("websockets.sync.client", reason="the websockets package is not installed")
ws_exceptions = pytest.importorskip("websockets.exceptions", reason="the websockets package is not installed")
pytestmark = pytest.mark.integration
KEY = "stream-test-key"
START = {"params": "paper-rig", "current": 1.0, "voltage": 12.0, "regularity": "continuous-voltage",
         "delay": 0.05, "dt": 0.001}


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("stream-server")
    srv = start_server(tmp, {"THRUSTSHAPE_DB_PATH": str(tmp / "jobs.sqlite"), "THRUSTSHAPE_API_KEY": KEY})
    try:
        yield srv
    finally:
        srv.stop()


def _connect(server: Server, **kw: Any) -> Any:
    return ws_client.connect(server.url.replace("http://", "ws://") + "/v1/stream", open_timeout=30, **kw)


def _refusal(ws: Any) -> tuple[dict[str, Any], int | None]:
    """The error frame and the close code that follows it."""
    msg = json.loads(ws.recv(timeout=30))
    while msg.get("type") == "samples":
        msg = json.loads(ws.recv(timeout=30))
    with pytest.raises(Exception):  # noqa: B017 - the closed connection: websockets' ConnectionClosed*
        ws.recv(timeout=30)
    return msg, ws.close_code


def test_stream_answers_are_the_core_shaper(server: Server, rig: MotorParams) -> None:
    t = np.arange(300) * 0.001
    f = 0.3 * np.sin(2 * np.pi * 3.0 * t)
    with _connect(server) as ws:
        ws.send(json.dumps({**START, "api_key": KEY}))
        ready = json.loads(ws.recv(timeout=30))
        assert ready["type"] == "ready" and ready["preview"] == 50
        got: dict[str, list[float]] = {"thrust": [], "current": [], "voltage": [], "t": []}
        for k in range(0, t.size, 100):
            ws.send(json.dumps({"t": t[k:k + 100].tolist(), "thrust": f[k:k + 100].tolist()}))
            msg = json.loads(ws.recv(timeout=30))
            assert msg["type"] == "samples"
            for name in got:
                got[name] += msg[name]
    ref = shape_profile(rig, stream_options(current=1.0, voltage=12.0, delay=0.05), t, f)
    np.testing.assert_array_equal(got["t"], t)
    for name in ("thrust", "current", "voltage"):
        np.testing.assert_array_equal(got[name], getattr(ref, name))


def test_stream_key_is_required(server: Server) -> None:
    with _connect(server) as ws:
        ws.send(json.dumps({**START, "api_key": "wrong"}))
        msg, code = _refusal(ws)
    assert msg["field"] == "api_key" and code == 1008
    with _connect(server, additional_headers={"Authorization": f"Bearer {KEY}"}) as ws:
        ws.send(json.dumps(START))
        assert json.loads(ws.recv(timeout=30))["type"] == "ready"


@pytest.mark.parametrize(("start", "frame", "field"), [
    ({"params": "/etc/hostname"}, None, "params"),
    ({"delay": 5.0}, None, "delay"),
    ({"speed": 3}, None, "speed"),
    ({}, {"t": [0.0, 0.001], "thrust": [0.1, "x"]}, "thrust.1"),
    ({}, {"t": list(np.arange(MAX_BATCH + 1) * 1e-3), "thrust": [0.0] * (MAX_BATCH + 1)}, "t"),
    ({}, {"t": [0.0, 0.004], "thrust": [0.1, 0.1]}, "t"),
])
def test_stream_bad_input_names_the_field(server: Server, start: dict, frame: dict | None, field: str) -> None:
    with _connect(server) as ws:
        ws.send(json.dumps({**START, "api_key": KEY, **start}))
        if frame is not None:
            assert json.loads(ws.recv(timeout=30))["type"] == "ready"
            ws.send(json.dumps(frame))
        msg, code = _refusal(ws)
    assert msg["type"] == "error" and msg["field"] == field, msg
    assert code in (1007, 1008)


def test_stream_binary_frame_is_refused(server: Server) -> None:
    with _connect(server) as ws:
        ws.send(b"\x00\x01")
        msg, code = _refusal(ws)
    assert msg["field"] == "frame" and code == 1003


def test_stream_rate_and_sessions_are_bounded(server: Server) -> None:
    with _connect(server) as ws:
        ws.send(json.dumps({**START, "api_key": KEY}))
        assert json.loads(ws.recv(timeout=30))["type"] == "ready"
        t0 = 0
        for _ in range(40):  # 8,000 samples sent at once: far above the sustained rate and the burst
            t = (np.arange(t0, t0 + MAX_BATCH) * 0.001).tolist()
            try:
                ws.send(json.dumps({"t": t, "thrust": [0.1] * MAX_BATCH}))
            except ws_exceptions.ConnectionClosed:
                break  # the server refused mid-burst and closed; its error frame is still queued, read below
            t0 += MAX_BATCH
        msg, code = _refusal(ws)
    assert msg["field"] == "rate" and code == 1008, (msg, code)
    with contextlib.ExitStack() as stack:
        for _ in range(MAX_SESSIONS):
            ws = stack.enter_context(_connect(server))
            ws.send(json.dumps({**START, "api_key": KEY}))
            assert json.loads(ws.recv(timeout=30))["type"] == "ready"
        with _connect(server) as extra:
            msg = json.loads(extra.recv(timeout=30))
        assert msg["field"] == "session"
    with _connect(server) as ws:  # the sessions closed: room again
        ws.send(json.dumps({**START, "api_key": KEY}))
        assert json.loads(ws.recv(timeout=30))["type"] == "ready"


def test_stream_example_is_the_papers_impedance_reference(server: Server) -> None:
    url = server.url + "/v1/stream/example?law=impedance&duration=2&amplitude=0.5"
    assert httpx.get(url, timeout=60).status_code == 401
    body = httpx.get(url, headers={"Authorization": f"Bearer {KEY}"}, timeout=60).json()
    ref = interaction_reference(Law.IMPEDANCE)  # the gallery's 4 s normalised reference, same law and constants
    thrust = np.array(body["thrust"])
    assert len(body["t"]) == 2001 and np.max(np.abs(thrust)) == pytest.approx(0.5)
    np.testing.assert_allclose(thrust / 0.5 * np.max(np.abs(ref.x2d[:2001])), ref.x2d[:2001], rtol=0, atol=1e-7)
    bad = httpx.get(server.url + "/v1/stream/example?duration=50", headers={"Authorization": f"Bearer {KEY}"},
                    timeout=60)
    assert bad.status_code == 422 and "duration" in bad.text


def test_stream_session_runs_in_its_own_process_and_its_death_is_reported(server: Server) -> None:
    """The shaper runs in a child of the server, not in it; killing that child closes the session with the
    reason (1011), the server lives on, and the next session gets a fresh process."""
    psutil = pytest.importorskip("psutil")
    server_proc = psutil.Process(server.proc.pid)
    frame = {"t": [0.0, 0.001], "thrust": [0.1, 0.1]}
    with _connect(server) as ws:
        ws.send(json.dumps({**START, "api_key": KEY}))
        ready = json.loads(ws.recv(timeout=30))
        pid = ready["pid"]
        assert pid != server.proc.pid and pid in {p.pid for p in server_proc.children(recursive=True)}
        ws.send(json.dumps(frame))
        assert json.loads(ws.recv(timeout=30))["type"] == "samples"
        psutil.Process(pid).kill()
        assert _gone(psutil, pid)
        ws.send(json.dumps({"t": [0.002], "thrust": [0.1]}))
        msg, code = _refusal(ws)
    assert msg["field"] == "session" and "process ended" in msg["reason"] and code == 1011, (msg, code)
    assert server.proc.poll() is None
    with _connect(server) as ws:
        ws.send(json.dumps({**START, "api_key": KEY}))
        again = json.loads(ws.recv(timeout=30))
        assert again["type"] == "ready" and again["pid"] not in (pid, server.proc.pid)
        ws.send(json.dumps(frame))
        assert json.loads(ws.recv(timeout=30))["type"] == "samples"
    assert _gone(psutil, again["pid"])  # the client left: its process is stopped


def _gone(psutil: Any, pid: int, timeout: float = 10.0) -> bool:
    """The process ``pid`` ended within ``timeout`` [s] (exited, or a zombie its parent has not reaped yet)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            if psutil.Process(pid).status() == psutil.STATUS_ZOMBIE:
                return True
        except psutil.NoSuchProcess:
            return True
        time.sleep(0.05)
    return False


def test_stream_session_frame_overrun_kills_its_process() -> None:
    """A frame past its hard timeout raises TaskTimeout and the session's process is killed; the shaper's own
    errors come back as the same ThrustshapeError leaf with field and reason."""
    psutil = pytest.importorskip("psutil")
    start = {**START, "bandwidth": 20.0}

    async def run() -> None:
        slow = StreamSession()
        try:
            assert (await slow.open(start, 60.0))["type"] == "ready"
            n = MAX_BATCH
            with pytest.raises(TaskTimeout):  # 200 samples cannot be shaped in 10 us
                await slow.push({"t": list(np.arange(n) * 1e-3), "thrust": [0.1] * n}, 1e-5)
            assert slow.pid is not None and _gone(psutil, slow.pid)
        finally:
            slow.close()
        bad = StreamSession()
        try:
            with pytest.raises(ThrustshapeError) as err:
                await bad.open({**start, "delay": 5.0}, 60.0)
            assert err.value.field == "delay"
        finally:
            bad.close()

    asyncio.run(run())


def test_stream_example_runs_in_the_worker_pool(server: Server) -> None:
    """The example is a pool task (the task log names it), not computed in the server process."""
    rid = f"example-{time.time_ns()}"
    url = server.url + "/v1/stream/example?law=admittance&duration=1&rate=500"
    got = httpx.get(url, headers={"Authorization": f"Bearer {KEY}", "X-Request-ID": rid}, timeout=60)
    assert got.status_code == 200 and len(got.json()["t"]) == 501, got.text
    pattern = rf"task id=[0-9a-f]{{12}} kind=stream_example duration_ms=\S+ outcome=ok request_id={rid}$"
    deadline = time.monotonic() + 10
    while not re.search(pattern, server.log.read_text(), re.M) and time.monotonic() < deadline:
        time.sleep(0.1)
    assert re.search(pattern, server.log.read_text(), re.M), server.log.read_text()[-2000:]
