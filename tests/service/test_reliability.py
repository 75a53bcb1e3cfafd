"""Nothing a request sends takes the server down or gets numbers outside the limits (issue #12), over real
HTTP: real uvicorn servers, real worker processes, a real SQLite file. One test per numbered finding:

1. a sampled profile spanning 1e6 s is a 422 before any work (it once grew a 23 GB grid in the server);
2. a fallback answer (here: behind a busy worker, 0.05 A) is within its limits or a 422 ``infeasible``;
3. store write failures (the database locked by another process past the busy timeout) neither stall nor lose
   batches and show in /healthz; a second server on the database refuses to start; a vanished data directory
   is a 503, not a 202;
4. (the Parquet bomb is in ``test_service_model_check``);
5. out-of-range numbers and non-numbers ("12", true) are 422s naming the field, never 500s;
6. the deadline covers the wait for a worker: behind a busy worker the answer comes within the deadline and
   says the queue ran out; a fallback that hangs is killed in its own process, not in the server;
7. the API key is checked before the body is read; /docs and /redoc load nothing from outside; a model-check
   error caused by the params' effects block is reported under ``params``.
"""

from __future__ import annotations

import json
import shutil
import socket
import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from tests.service.test_service_support import Server, digest, mission, problem, start_server

pytestmark = pytest.mark.integration

KEY = "k3y"
AUTH = {"Authorization": f"Bearer {KEY}"}
DEADLINE = 4.0


def _cpu_seconds(pid: int) -> float:
    """User + system CPU time [s] of one process (its threads included, its children not), from /proc."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / 100.0


@pytest.fixture(scope="module")
def guarded(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    """API key set; one solver worker that batch items keep busy for 6 s; a 4 s optimise deadline."""
    tmp = tmp_path_factory.mktemp("guarded")
    srv = start_server(tmp, {"TS_TEST_TASKS": "slow-batch", "TS_TEST_ITEM_SECONDS": "6", "THRUSTSHAPE_API_KEY": KEY,
                             "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"),
                             "THRUSTSHAPE_OPTIMIZE_DEADLINE_S": str(DEADLINE), "THRUSTSHAPE_FALLBACK_RESERVE_S": "2"},
                       warm=True, timeout=180)
    yield srv
    srv.stop()


@pytest.fixture()
def http(guarded: Server) -> Iterator[httpx.Client]:
    with httpx.Client(base_url=guarded.url, headers=AUTH, timeout=60.0) as c:
        yield c


def test_1_a_huge_profile_span_is_refused_before_any_work(http: httpx.Client) -> None:
    body = {"name": "span", "time_limit_s": 1.0, "profile": {"t": [0.0, 1.0, 1e6], "thrust": [0.3, 0.0, -0.3]}}
    t0 = time.monotonic()
    p = problem(http.post("/v1/references/optimize", json=body), 422)
    assert p["field"] == "profile.t" and "100 s" in p["reason"] and time.monotonic() - t0 < 2.0
    stretched = {**mission("long", duration=60.0), "retiming": {"max_stretch": 4.0}}  # 60 s x 4 > 200 s
    assert problem(http.post("/v1/references/optimize", json=stretched), 422)["field"] == "retiming.max_stretch"
    # 300 reversals need 2408 collocation intervals (8 a phase): refused before a solver is built for them
    sines = {"name": "sines", "segments": [{"kind": "sine", "duration": 15.0, "amplitude": 0.5, "period": 0.1}]}
    p = problem(http.post("/v1/batches", json={"missions": [mission("ok"), sines]}), 422)
    assert p["field"] == "missions.1.segments" and "reversals need at least 8" in p["reason"], p
    assert http.get("/healthz").status_code == 200


BAD_INPUTS: list[tuple[str, dict[str, Any], str]] = [
    # durations of a denormal 5e-324 s (found by schemathesis, session 8): a ZeroDivisionError in the worker and in
    # the fallback (a 500) before the shortest segment and span were bounded
    ("/v1/references/optimize", {"name": "m", "segments": [{"kind": "hold", "duration": 5e-324, "thrust": 0.0}] * 3},
     "segments.0.duration"),
    ("/v1/references/optimize", {"name": "m", "segments": [{"kind": "hold", "duration": 2e-4, "thrust": 0.1}] * 3},
     "segments"),
    ("/v1/references/optimize", {"name": "m", "profile": {"t": [0.0, 5e-324], "thrust": [0.1, -0.1]}}, "profile.t"),
    ("/v1/references/optimize", mission("m", amplitude=1e308), "segments.0.thrust"),
    ("/v1/references/optimize", {**mission("m"), "time_limit_s": "12"}, "time_limit_s"),
    ("/v1/references/optimize", {**mission("m"), "limits": {"current": True}}, "limits.current"),
    ("/v1/references/optimize", {**mission("m"), "params": {**json.loads(
        Path("ocp/presets/paper-rig.json").read_text()), "notes": None, "effects": {"input_delay": {"delay": 1e-300}}}},
     "params"),
    ("/v1/references/optimize", {**mission("m"), "params": {**json.loads(
        Path("ocp/presets/paper-rig.json").read_text()), "notes": None, "effects": {"stribeck": {"omega_s": 1e-300}}}},
     "params"),
    ("/v1/references/optimize", {**mission("m"), "params": {**json.loads(
        Path("ocp/presets/paper-rig.json").read_text()), "notes": None,
        "effects": {"coulomb_friction": {"tau_c": 0.003, "omega_eps": 0}}}}, "params"),
    ("/v1/references/analytic", {"amplitude": 0.4, "period": 1.0, "q": 20, "phase": 1e308}, "phase"),
    ("/v1/references/analytic", {"amplitude": 1e308, "period": 1.0, "q": 2}, "amplitude"),
    ("/v1/references/analytic", {"amplitude": "0.4", "period": 1.0, "q": 2}, "amplitude"),
]


@pytest.mark.parametrize(("path", "body", "field"), BAD_INPUTS, ids=[f"{f}-{i}" for i, (_, _, f) in
                                                                    enumerate(BAD_INPUTS)])
def test_5_bad_numbers_are_422_naming_the_field(http: httpx.Client, path: str, body: dict[str, Any],
                                                field: str) -> None:
    p = problem(http.post(path, json=body), 422)
    assert p["field"].startswith(field), p


def test_6_2_behind_a_busy_worker_the_answer_keeps_the_deadline_and_the_limits(http: httpx.Client) -> None:
    """A batch item holds the only solver worker for 6 s; an optimise with a 4 s deadline gets the fallback
    (from its own worker process) within the deadline, its reason blames the queue, and the 0.05 A limit holds
    on the integration grid (or the answer is a 422 naming the limit)."""
    accepted = http.post("/v1/batches", json={"missions": [mission("busy")]})
    assert accepted.status_code == 202
    deadline = time.monotonic() + 30
    while http.get(f"/v1/batches/{accepted.json()['id']}").json()["counts"]["running"] == 0:
        assert time.monotonic() < deadline
        time.sleep(0.1)
    t0 = time.monotonic()
    r = http.post("/v1/references/optimize", json={**mission("tiny", amplitude=0.4), "limits": {"current": 0.05}})
    elapsed = time.monotonic() - t0
    assert elapsed <= DEADLINE + 0.5, elapsed
    if r.status_code == 422:
        assert r.json()["code"] == "infeasible" and r.json()["field"].startswith("limits")
        return
    assert r.status_code == 200, r.text[:300]
    out = r.json()
    assert out["source"] == "analytic-fallback" and "(queue)" in out["reason"], out["reason"]
    v = out["verification"]
    assert v["path_ok"] and v["max_abs_current"] <= 0.05 * 1.001 and v["max_abs_voltage"] <= 12.0 * 1.001
    assert max(abs(i) for i in out["current"]) <= 0.05 * 1.001


def test_7_the_key_is_checked_before_the_body_is_read(guarded: Server) -> None:
    """A request announcing a 30 MB upload without the key gets its 401 while the body is still unsent."""
    host, port = guarded.url.removeprefix("http://").split(":")
    with socket.create_connection((host, int(port)), timeout=10) as s:
        s.sendall(b"POST /v1/model-check/check HTTP/1.1\r\nHost: x\r\nContent-Type: multipart/form-data; "
                  b"boundary=b\r\nContent-Length: 30000000\r\n\r\n")
        head = s.recv(4096).decode(errors="replace")
    assert head.startswith("HTTP/1.1 401") and "www-authenticate: bearer" in head.lower()
    r = httpx.post(guarded.url + "/v1/references/optimize", content=b"{not json", timeout=10)
    assert r.status_code == 401  # not 422: the body was never parsed


def test_7_docs_are_served_from_the_package(http: httpx.Client, guarded: Server) -> None:
    for page in ("/docs", "/redoc"):
        html = http.get(page).text
        assert "http://" not in html and "https://" not in html and "/docs/assets/" in html, page
    for asset in ("swagger-ui-bundle.js", "swagger-ui.css", "redoc.standalone.js"):
        r = httpx.get(f"{guarded.url}/docs/assets/{asset}", timeout=10)  # public: no data in them
        assert r.status_code == 200 and len(r.content) > 100_000
    assert http.get("/docs/assets/jobs.db").status_code == 404


def test_7_model_check_effect_errors_name_params(http: httpx.Client) -> None:
    params = {**json.loads(Path("ocp/presets/paper-rig.json").read_text()), "notes": None,
              "effects": {"coulomb_friction": {"tau_c": 0.003, "omega_eps": 0}}}
    log = "t,voltage,current,omega,thrust\n" + "\n".join(f"{k * 1e-3:.3f},1,0.1,10,0.01" for k in range(200))
    r = http.post("/v1/model-check/check", files={"log": ("log.csv", log.encode())},
                  data={"params": json.dumps(params)})
    p = problem(r, 422)
    assert p["field"].startswith("params") and p["form_field"] == "params" and "omega_eps" in p["reason"]


@pytest.fixture(scope="module")
def hanging(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("hang-both")
    srv = start_server(tmp, {"TS_TEST_TASKS": "hang-both", "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"),
                             "THRUSTSHAPE_OPTIMIZE_DEADLINE_S": "3", "THRUSTSHAPE_FALLBACK_RESERVE_S": "1"},
                       warm=True, timeout=180)
    yield srv
    srv.stop()


def test_6_1_a_runaway_fallback_is_killed_in_its_own_process(hanging: Server) -> None:
    """Solver and fallback both hang: 504 at the deadline naming both parts; afterwards the server process
    burns no CPU (the fallback ran, and was killed, in a worker process) and keeps answering."""
    t0 = time.monotonic()
    r = httpx.post(hanging.url + "/v1/references/optimize", json=mission("m"), timeout=30)
    assert time.monotonic() - t0 <= 3.0 + 0.7
    p = problem(r, 504)
    assert "solver did not finish" in p["detail"] and "fallback ran out while computing (run)" in p["detail"]
    before = _cpu_seconds(hanging.proc.pid)
    time.sleep(2.0)
    assert _cpu_seconds(hanging.proc.pid) - before < 0.5  # a thread in the server would burn ~2 s here
    assert httpx.get(hanging.url + "/healthz", timeout=5).status_code == 200
    assert "killing and respawning" in hanging.log.read_text()


@pytest.fixture()
def faulty(tmp_path: Path) -> Iterator[tuple[Server, Path]]:
    data = tmp_path / "data"
    srv = start_server(tmp_path, {"TS_TEST_TASKS": "slow-batch", "TS_TEST_ITEM_SECONDS": "1.0",
                                  "THRUSTSHAPE_DB_PATH": str(data / "jobs.db"),
                                  "THRUSTSHAPE_STORE_BUSY_TIMEOUT_S": "0.2"}, warm=True, timeout=180)
    yield srv, data / "jobs.db"
    srv.stop()


def _wait_done(c: httpx.Client, batch: str, timeout: float = 60.0) -> dict[str, Any]:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        s = c.get(f"/v1/batches/{batch}").json()
        if s["status"] in ("done", "failed"):
            return s
        time.sleep(0.2)
    raise AssertionError(f"batch {batch} not finished: {s}")


def test_3_store_failures_neither_stall_nor_lose_batches(faulty: tuple[Server, Path], tmp_path: Path) -> None:
    srv, db = faulty
    missions = [mission(f"m{i}", amplitude=0.1 + 0.01 * i) for i in range(6)]
    with httpx.Client(base_url=srv.url, timeout=30) as c:
        batch = c.post("/v1/batches", json={"missions": missions}).json()["id"]
        end = time.monotonic() + 20.0
        while c.get(f"/v1/batches/{batch}").json()["counts"]["running"] == 0:  # an item is being computed
            assert time.monotonic() < end
            time.sleep(0.05)
        lock = sqlite3.connect(db, isolation_level=None)
        lock.execute("BEGIN EXCLUSIVE")  # another process holds the database: every write times out
        try:
            refused = c.post("/v1/batches", json={"missions": [mission("late")]})
            assert problem(refused, 503)["title"] == "Store unavailable"  # not a 202 for an unstored batch
            end = time.monotonic() + 20.0
            # outcomes kept, not thrown away; "retrying" once a write has failed (an outcome is held from the moment
            # it is computed, the write that fails takes the store's lock timeout: polled, not read once)
            while (health := c.get("/healthz")).json()["runner"]["state"] != "retrying":
                assert time.monotonic() < end, health.json()
                time.sleep(0.2)
            assert health.status_code == 503 and health.json()["runner"]["unsaved"] >= 1
            assert "locked" in health.json()["runner"]["last_error"]
        finally:
            lock.execute("ROLLBACK")
            lock.close()
        status = _wait_done(c, batch)
        assert status["status"] == "done" and status["counts"]["done"] == 6
        results = c.get(f"/v1/batches/{batch}/results").json()["results"]
        assert [r["index"] for r in results] == list(range(6))
        assert [r["result"]["name"] for r in results] == [f"m{i}" for i in range(6)]
        assert [r["result"]["digest"] for r in results] == [digest(_stored(db, batch, i)) for i in range(6)]
        assert all(r["attempts"] == 1 for r in results)  # each ran once: none lost, none run twice
        assert c.get("/healthz").json()["runner"]["state"] == "running"

        second = None
        with pytest.raises(RuntimeError) as refused_start:
            second = start_server(tmp_path, {"TS_TEST_TASKS": "slow-batch", "THRUSTSHAPE_DB_PATH": str(db)},
                                  timeout=60)
        if second is not None:
            second.stop()
        assert "another thrustshape server" in str(refused_start.value)

        shutil.rmtree(db.parent)  # the data directory vanishes under the running server
        gone = c.post("/v1/batches", json={"missions": [mission("after")]})
        assert "vanished" in problem(gone, 503)["detail"]
        health = c.get("/healthz")
        assert health.status_code == 503 and health.json()["store"]["ok"] is False


def _stored(db: Path, batch: str, index: int) -> dict[str, Any]:
    with sqlite3.connect(db) as conn:
        row = conn.execute("SELECT mission FROM items WHERE batch_id = ? AND idx = ?", (batch, index)).fetchone()
    return dict(json.loads(row[0]))
