"""Worker processes: real spawned processes running real CPU-bound tasks; timeouts kill them, a dead
worker is replaced, a full queue refuses at once; and, over HTTP, a solve that hangs is answered by
the analytic fallback within its deadline while the server stays up."""

from __future__ import annotations

import asyncio
import os
import sys
import threading
import time
from collections.abc import Iterator

import httpx
import pytest

from ocp.errors import MissionError, ThrustshapeError
from service.settings import Settings
from service.tasks import available_tasks
from service.workers import QueueFull, TaskFailed, TaskTimeout, WorkerPool, report_phase
from tests.service.test_service_support import Server, _burn, die, digest, hang, mission, spin, start_server

_BUILT: dict[str, float] = {}  # inside a worker: the "solvers" this process built (key -> seconds it took)


def _user_error(payload: dict[str, object]) -> dict[str, object]:
    raise MissionError("profile.t", "must be strictly increasing")


def slow_build(payload: dict[str, object]) -> dict[str, object]:
    """Builds (CPU burn of ``build_s``) and caches a "solver" per ``key`` on first use, reporting the build as
    the collocation cache does; then "solves" (``solve_s``)."""
    key = str(payload["key"])
    cached = key in _BUILT
    if not cached:
        report_phase("build")
        t0 = time.perf_counter()
        _burn(float(payload["build_s"]))  # type: ignore[arg-type]
        _BUILT[key] = time.perf_counter() - t0
        report_phase("built")
    _burn(float(payload.get("solve_s", 0.01)))  # type: ignore[arg-type]
    return {"pid": os.getpid(), "cached": cached, "built": sorted(_BUILT)}


def oom_score_adj(payload: dict[str, object]) -> dict[str, int]:
    with open("/proc/self/oom_score_adj") as f:
        return {"adj": int(f.read())}


@pytest.mark.skipif(not os.path.exists("/proc/self/oom_score_adj"), reason="Linux's OOM killer")
def test_workers_go_before_the_server_when_memory_runs_out() -> None:
    """A worker's ``oom_score_adj`` is the server's + 500 (at most 1000): a request that exhausts memory costs its
    own worker (replaced, as a worker that dies is), not the server."""
    async def scenario() -> int:
        pool = WorkerPool(1, queue_size=1, retry_after=1, preload=())
        try:
            return int((await pool.run(oom_score_adj, {}, timeout=60))["adj"])
        finally:
            pool.close()

    own = oom_score_adj({})["adj"]
    assert own < 1000 and asyncio.run(scenario()) == min(1000, own + 500)


def allocate(payload: dict[str, object]) -> dict[str, int]:
    """Touch ``payload["mib"]`` MiB of doubles."""
    import numpy as np

    a = np.ones(int(str(payload["mib"])) << 17)
    return {"pid": os.getpid(), "n": int(a.size)}


@pytest.mark.skipif(sys.platform != "linux", reason="Linux's RLIMIT_DATA")
def test_a_task_over_the_worker_memory_cap_is_a_user_error_and_the_worker_goes_on() -> None:
    """With ``memory_mib`` a task allocating past the cap is answered as a user error (field ``request``, naming the
    cap and its setting) by the same worker, which then serves the next call; without the cap the same task runs
    (the control: the cap, not the machine, refused it)."""
    async def scenario(cap: int | None) -> list[object]:
        pool = WorkerPool(1, queue_size=1, retry_after=1, preload=(), memory_mib=cap)
        try:
            first = await pool.run(allocate, {"mib": 64}, timeout=60)
            try:
                big: object = await pool.run(allocate, {"mib": 1536}, timeout=60)
            except ThrustshapeError as exc:
                big = exc
            again = await pool.run(allocate, {"mib": 64}, timeout=60)
            return [first["pid"], big, again["pid"]]
        finally:
            pool.close()

    pid, refused, after = asyncio.run(scenario(768))
    assert isinstance(refused, ThrustshapeError) and refused.field == "request"
    assert "768 MiB, THRUSTSHAPE_WORKER_MEMORY_MB" in refused.reason and after == pid
    _, ran, _ = asyncio.run(scenario(None))
    assert isinstance(ran, dict) and ran["n"] == 1536 << 17


def test_the_memory_cap_setting_is_checked() -> None:
    with pytest.raises(ValueError, match="worker_memory_mb"):
        Settings(worker_memory_mb=100)
    assert Settings(worker_memory_mb=2048).worker_memory_mb == 2048


def test_deadline_during_build_keeps_the_worker_and_its_build() -> None:
    """A call whose deadline runs out while its worker builds a solver is answered at its deadline (phase
    ``build``); the worker is not killed: it finishes the build, skips the abandoned solve and serves the next
    call from its cache. A build past the pool's build limit is killed."""
    async def scenario() -> None:
        pool = WorkerPool(1, queue_size=1, retry_after=1, preload=(), build_limit=20.0)
        try:
            # first call: the worker imports this module (seconds under pytest), outside the deadlines below
            pid = (await pool.run(slow_build, {"key": "warm", "build_s": 0.0}, timeout=60))["pid"]
            t0 = time.monotonic()
            with pytest.raises(TaskTimeout) as late:
                await pool.run(slow_build, {"key": "a", "build_s": 2.5, "solve_s": 30.0}, timeout=0.8)
            assert late.value.phase == "build" and "building the solver" in str(late.value)
            assert time.monotonic() - t0 < 1.6  # answered at its deadline, not after the build
            again = await pool.run(slow_build, {"key": "a", "build_s": 2.5}, timeout=10)
            # same process, solver from its cache, and the abandoned 30 s solve was skipped
            assert again == {"pid": pid, "cached": True, "built": ["a", "warm"]}
            assert time.monotonic() - t0 < 2.5 + 5.0

            with pytest.raises(TaskTimeout):  # a call that times out while solving is still killed
                await pool.run(slow_build, {"key": "a", "build_s": 0.0, "solve_s": 30.0}, timeout=0.8)
            assert pid not in pool.pids()
        finally:
            pool.close()
        capped = WorkerPool(1, queue_size=1, retry_after=1, preload=(), build_limit=1.5)
        try:
            pid = (await capped.run(slow_build, {"key": "warm", "build_s": 0.0}, timeout=60))["pid"]
            with pytest.raises(TaskTimeout) as late:
                await capped.run(slow_build, {"key": "b", "build_s": 60.0}, timeout=0.5)
            assert late.value.phase == "build"
            t0 = time.monotonic()
            after = await capped.run(slow_build, {"key": "b", "build_s": 0.1}, timeout=60, wait=True)
            assert after["pid"] != pid and after["cached"] is False  # killed at the build limit, built anew
            assert time.monotonic() - t0 < 30.0
        finally:
            capped.close()

    asyncio.run(scenario())


def note_pid(payload: dict[str, object]) -> dict[str, object]:
    """A warm-up task: appends this process's pid to the file ``payload["file"]`` names."""
    with open(str(payload["file"]), "a", encoding="utf-8") as fh:
        fh.write(f"{os.getpid()}\n")
    return {}


def test_a_process_that_replaces_a_killed_one_is_warmed_up_before_its_first_call(tmp_path: object) -> None:
    """The pool's warm-up task runs on each process at the start and again on the process that replaces one
    killed at its timeout, before that process takes a call."""
    noted = os.path.join(str(tmp_path), "warmed")

    async def scenario() -> None:
        pool = WorkerPool(1, queue_size=0, retry_after=1, preload=("tests.service.test_service_workers",))
        try:
            await pool.warm(note_pid, {"file": noted})
            first = pool.pids()[0]
            with pytest.raises(TaskTimeout):
                await pool.run(hang, {}, timeout=1.0)
            out = await pool.run(spin, {"seconds": 0.01}, timeout=60)
            assert out["pid"] != first
            with open(noted, encoding="utf-8") as fh:
                assert fh.read().split() == [str(first), str(out["pid"])]  # warmed before the call it served
        finally:
            pool.close()

    asyncio.run(scenario())


def test_pool_runs_timeouts_restarts_and_refuses() -> None:
    async def scenario() -> None:
        pool = WorkerPool(1, queue_size=1, retry_after=3, preload=())
        try:
            out = await pool.run(spin, {"seconds": 0.05, "x": 1}, timeout=30)
            assert out["digest"] == digest({"seconds": 0.05, "x": 1})
            first_pid = out["pid"]
            assert first_pid != os.getpid() and first_pid in pool.pids()

            t0 = time.monotonic()
            with pytest.raises(TaskTimeout):
                await pool.run(hang, {}, timeout=1.0)
            assert time.monotonic() - t0 < 5.0  # killed at the timeout, not after the task
            assert first_pid not in pool.pids()  # the runaway process is gone...
            again = await pool.run(spin, {"seconds": 0.01}, timeout=60)  # ...and a fresh one serves
            assert again["pid"] != first_pid

            with pytest.raises(TaskFailed, match="died"):
                await pool.run(die, {}, timeout=30)
            assert (await pool.run(spin, {"seconds": 0.01}, timeout=60))["pid"] != again["pid"]

            with pytest.raises(MissionError) as err:  # a core error crosses the process boundary intact
                await pool.run(_user_error, {}, timeout=30)
            assert err.value.field == "profile.t" and "increasing" in err.value.reason

            # capacity 2 (1 worker + 1 waiting): the third concurrent call is refused at once
            running = [asyncio.create_task(pool.run(spin, {"seconds": 1.0, "i": i}, timeout=30)) for i in range(2)]
            await asyncio.sleep(0.2)
            t0 = time.monotonic()
            with pytest.raises(QueueFull) as full:
                await pool.run(spin, {"seconds": 0.01}, timeout=30)
            assert full.value.retry_after == 3 and time.monotonic() - t0 < 0.1
            assert (await pool.run(spin, {"seconds": 0.01}, timeout=30, wait=True))["pid"] > 0  # wait=True queues
            assert [r["digest"] for r in await asyncio.gather(*running)] == [
                digest({"seconds": 1.0, "i": i}) for i in range(2)]
        finally:
            pool.close()

    asyncio.run(scenario())


@pytest.fixture(scope="module")
def hanging(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """Server whose optimiser never returns; deadline 3 s; one worker, no waiting room."""
    tmp = tmp_path_factory.mktemp("hang")
    srv = start_server(tmp, {"TS_TEST_TASKS": "hang-optimize", "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"),
                             "THRUSTSHAPE_OPTIMIZE_DEADLINE_S": "3", "THRUSTSHAPE_FALLBACK_RESERVE_S": "1",
                             "THRUSTSHAPE_QUEUE_SIZE": "0", "THRUSTSHAPE_RETRY_AFTER_S": "2"}, warm=True)
    yield srv
    srv.stop()


needs_fallback = pytest.mark.skipif(available_tasks().fallback is None, reason="ocp.optimize.solve is not installed")


@needs_fallback
@pytest.mark.integration
def test_hanging_solve_answers_fallback_within_deadline(hanging: Server) -> None:
    with httpx.Client(base_url=hanging.url, timeout=30) as http:
        http.post("/v1/references/analytic", json={"amplitude": 0.5, "period": 1.0, "q": 2, "rate": 10})  # warm
        t0 = time.monotonic()
        r = http.post("/v1/references/optimize", json=mission("stuck"))
        elapsed = time.monotonic() - t0
        assert r.status_code == 200, r.text[:500]
        out = r.json()
        assert out["source"] == "analytic-fallback"
        assert "deadline" in out["reason"] and "2 s" in out["reason"]
        assert len(out["t"]) == len(out["voltage"]) > 2
        assert elapsed < 3.0 + 0.5, elapsed  # the 3 s deadline, plus HTTP overhead
        assert elapsed > 1.9  # it really waited for the solver (2 s budget) before falling back
        # the killed worker was replaced: the server still computes
        ok = http.post("/v1/references/analytic", json={"amplitude": 0.5, "period": 1.0, "q": 2, "rate": 10})
        assert ok.status_code == 200


@pytest.mark.integration
def test_full_queue_answers_503_with_retry_after(hanging: Server) -> None:
    """One worker, queue 0: while a hanging solve holds the worker, other requests get 503 at once."""
    results: list[httpx.Response] = []

    def occupy() -> None:
        with httpx.Client(base_url=hanging.url, timeout=30) as c:
            results.append(c.post("/v1/references/optimize", json=mission("stuck")))

    if available_tasks().fallback is None:
        pytest.skip("ocp.optimize.solve is not installed")
    th = threading.Thread(target=occupy)
    th.start()
    time.sleep(0.5)
    with httpx.Client(base_url=hanging.url, timeout=30) as http:
        t0 = time.monotonic()
        r = http.post("/v1/references/analytic", json={"amplitude": 0.5, "period": 1.0, "q": 2, "rate": 10})
        assert time.monotonic() - t0 < 0.5
        assert r.status_code == 503 and r.headers["retry-after"] == "2"
        assert r.headers["content-type"].startswith("application/problem+json")
        assert http.get("/healthz").status_code == 200  # the event loop is free meanwhile
    th.join(30)
    assert results and results[0].status_code == 200 and results[0].json()["source"] == "analytic-fallback"
