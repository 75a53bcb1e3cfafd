"""Shared helpers for the service tests (no tests here): real CPU-bound task functions that run in
the worker processes, an app factory for ``uvicorn --factory``, and a real uvicorn server launcher.

The task functions are real work in real processes, not mocks: ``spin`` burns CPU for a given time,
``hang`` never returns, ``die`` kills its own process.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import signal
import socket
import subprocess
import sys
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import httpx

from service.tasks import TaskSet, analytic_reference, available_tasks

ROOT = Path(__file__).resolve().parents[2]


def _burn(seconds: float) -> int:
    end, n = time.perf_counter() + seconds, 0
    while time.perf_counter() < end:
        n += 1
    return n


def spin(payload: dict[str, Any]) -> dict[str, Any]:
    """Burn CPU for ``payload["seconds"]``; answer with the payload's digest and the worker pid."""
    _burn(float(payload.get("seconds", 0.1)))
    return {"digest": digest(payload), "pid": os.getpid()}


def hang(payload: dict[str, Any]) -> dict[str, Any]:
    """A solve that never finishes (busy loop)."""
    while True:
        _burn(1.0)


def die(payload: dict[str, Any]) -> dict[str, Any]:
    """The worker process dies mid-task (as a segfaulting solver would)."""
    os.kill(os.getpid(), signal.SIGKILL)
    return {}


def digest(obj: Any) -> str:
    return hashlib.sha256(json.dumps(obj, sort_keys=True).encode()).hexdigest()


def slow_item(mission: dict[str, Any]) -> dict[str, Any]:
    """A batch item that takes ``TS_TEST_ITEM_SECONDS`` of CPU; its result is a function of the mission
    (plus ``pid``/``finished_at``, which tell executions apart)."""
    _burn(float(os.environ.get("TS_TEST_ITEM_SECONDS", "0.3")))
    return {"source": "test", "status": "ok", "name": mission["name"], "digest": digest(mission),
            "pid": os.getpid(), "finished_at": time.time()}


def structure_key_noting_pid(mission: dict[str, Any]) -> str | None:
    """:func:`service.tasks.structure_key`, appending the pid of the process that computed it to the file
    ``TS_TEST_KEY_PIDS`` names (where a batch runner's keys were computed)."""
    from service.tasks import structure_key

    with open(os.environ["TS_TEST_KEY_PIDS"], "a", encoding="utf-8") as fh:
        fh.write(f"{os.getpid()}\n")
    return structure_key(mission)


def broken_key(mission: dict[str, Any]) -> str:
    """An affinity key function that fails as a bug would (not a core error)."""
    raise RuntimeError("key function broken")


def task_set(kind: str) -> TaskSet:
    """Task sets the factory can serve: ``real`` (installed backends), ``slow-batch``, ``hang-optimize``,
    ``hang-both`` (solver and fallback never return)."""
    real = available_tasks()
    if kind == "slow-batch":
        return TaskSet(analytic=analytic_reference, optimize=real.optimize, fallback=real.fallback,
                       compare=real.compare, batch_item=slow_item, model_check=real.model_check)
    if kind == "hang-both":
        return TaskSet(analytic=analytic_reference, optimize=hang, fallback=hang, batch_item=slow_item)
    if kind == "hang-optimize":
        return TaskSet(analytic=analytic_reference, optimize=hang, fallback=real.fallback, batch_item=slow_item)
    return real


def make_app() -> Any:
    """``uvicorn --factory tests.service.test_service_support:make_app``; ``TS_TEST_TASKS`` picks the task set."""
    from service.app import create_app
    from service.settings import Settings

    return create_app(Settings(), tasks=task_set(os.environ.get("TS_TEST_TASKS", "real")))


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


@dataclass
class Server:
    proc: subprocess.Popen[bytes]
    url: str
    log: Path

    def kill(self) -> None:
        """SIGKILL: no shutdown hooks, no flushing."""
        self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(10)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(5)


def start_server(tmp: Path, env: dict[str, str], *, port: int | None = None, factory: bool = True,
                 timeout: float = 90.0, warm: bool = False) -> Server:
    """A real uvicorn server on 127.0.0.1 (``thrustshape serve`` when ``factory`` is False); ``warm``: also
    wait until /healthz says every worker process has started. One solver and one fallback worker unless ``env``
    says otherwise (each process imports the solver stack and warms up: seconds of CPU per server start)."""
    port = port or free_port()
    full_env = {**os.environ, "THRUSTSHAPE_WORKERS": "1", "THRUSTSHAPE_FALLBACK_WORKERS": "1", **env}
    log = tmp / f"server-{port}-{time.time_ns()}.log"
    if factory:
        cmd = [sys.executable, "-m", "uvicorn", "--factory", "tests.service.test_service_support:make_app",
               "--host", "127.0.0.1", "--port", str(port), "--log-level", "warning"]
    else:
        cmd = [sys.executable, "-m", "clients.cli", "serve", "--host", "127.0.0.1", "--port", str(port)]
    with log.open("wb") as fh:
        proc = subprocess.Popen(cmd, cwd=ROOT, env=full_env, stdout=fh, stderr=subprocess.STDOUT)
    url = f"http://127.0.0.1:{port}"
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if proc.poll() is not None:
            raise RuntimeError(f"server exited with {proc.returncode}:\n{log.read_text()}")
        with contextlib.suppress(httpx.TransportError):
            r = httpx.get(url + "/healthz", timeout=1.0)
            if r.status_code == 200 and (not warm or all(
                    w is None or w["ready"] == w["size"] for w in (r.json().get("workers"),
                                                                  r.json().get("fallback_workers")))):
                return Server(proc, url, log)
        time.sleep(0.1)
    proc.kill()
    proc.wait(10)  # reaped here: an unreaped Popen warns later, inside whichever test then runs
    raise RuntimeError(f"server did not come up in {timeout} s:\n{log.read_text()}")


@contextlib.contextmanager
def running_server(tmp: Path, env: dict[str, str], **kw: Any) -> Iterator[Server]:
    server = start_server(tmp, env, **kw)
    try:
        yield server
    finally:
        server.stop()


def mission(name: str, amplitude: float = 0.3, duration: float = 1.0, **extra: Any) -> dict[str, Any]:
    """A small reversal mission (+a -> -a) as a JSON mapping."""
    return {"name": name, "segments": [{"kind": "hold", "duration": 0.2, "thrust": amplitude},
                                       {"kind": "reversal", "duration": duration, "to": -amplitude},
                                       {"kind": "hold", "duration": 0.2, "thrust": -amplitude}], **extra}


def problem(r: httpx.Response, status: int) -> dict[str, Any]:
    """The problem+json body of ``r``, asserting its status and media type."""
    assert r.status_code == status, r.text[:500]
    assert r.headers["content-type"].startswith("application/problem+json")
    body: dict[str, Any] = r.json()
    assert body["status"] == status
    return body
