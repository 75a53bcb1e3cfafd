"""Every route over real HTTP: a uvicorn subprocess, one worker process, a SQLite file in tmp.

Batch items run a real CPU-bound test task (``slow_item``) so the batch machinery is tested
independently of the optimiser; the optimiser/compare routes are tested when the core offers them.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from typing import Any

import httpx
import pytest

from service.tasks import available_tasks
from tests.service.test_service_support import Server, mission, problem, start_server

pytestmark = pytest.mark.integration

BODY_LIMIT = 200_000


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("api")
    env = {"TS_TEST_TASKS": "slow-batch", "TS_TEST_ITEM_SECONDS": "0.05", "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"),
           "THRUSTSHAPE_MAX_BODY_BYTES": str(BODY_LIMIT), "THRUSTSHAPE_MAX_BATCH_MISSIONS": "5",
           "THRUSTSHAPE_MAX_INTERVALS": "300", "THRUSTSHAPE_MAX_PROFILE_SAMPLES": "5000"}
    srv = start_server(tmp, env)
    yield srv
    srv.stop()


def test_healthz_and_info(http: httpx.Client) -> None:
    health = http.get("/healthz").json()
    assert health["status"] == "ok" and health["store"] == {"ok": True, "detail": None}
    assert health["runner"]["state"] == "running" and health["workers"]["alive"] == health["workers"]["size"] == 1
    info = http.get("/v1/info").json()
    assert info["presets"] == ["paper-rig", "paper-rig-revs"]
    assert "continuous-voltage" in info["regularities"]
    assert info["limits"]["max_batch_missions"] == 5
    assert info["limits"]["max_body_bytes"] == BODY_LIMIT
    assert info["features"]["batches"] is True
    assert info["workers"] == 1 and info["batch_backend"] == "local"


def test_openapi_and_docs(http: httpx.Client) -> None:
    spec = http.get("/openapi.json").json()
    assert "/v1/references/analytic" in spec["paths"] and "/v1/batches" in spec["paths"]
    assert "/healthz" in spec["paths"]
    docs = http.get("/docs")
    assert docs.status_code == 200 and "swagger" in docs.text.lower()


def test_analytic_sin(http: httpx.Client) -> None:
    r = http.post("/v1/references/analytic", json={"amplitude": 0.5, "period": 2.0, "q": 2, "rate": 100})
    assert r.status_code == 200, r.text
    ref = r.json()
    assert len(ref["t"]) == 201 and ref["t"][-1] == pytest.approx(2.0)
    # F(T/4) = A sin^5(pi/2) = A
    assert ref["thrust"][50] == pytest.approx(0.5, rel=1e-12)
    assert ref["unbounded"]["voltage"] is False
    assert [c["p"] for c in ref["crossings"]] == [5, 5, 5]


def test_analytic_unbounded_samples_are_strings(http: httpx.Client) -> None:
    ref = http.post("/v1/references/analytic", json={"amplitude": 0.5, "period": 2.0, "q": 0, "rate": 10}).json()
    assert ref["unbounded"]["current"] is True
    assert ref["current"][0] in ("inf", "-inf")  # the crossing at t = 0: unbounded, never NaN
    assert all(isinstance(v, float) for v in ref["thrust"])


def test_analytic_design_within_limits(http: httpx.Client) -> None:
    body = {"amplitude": 0.3, "limits": {"current": 2.0, "voltage": 12.0}, "regularity": "continuous-voltage",
            "rate": 200}
    r = http.post("/v1/references/analytic", json=body)
    assert r.status_code == 200, r.text
    ref = r.json()
    d = ref["design"]
    assert d["q"] == 2 and d["amplitude"] == 0.3
    assert d["peak_current"] <= 2.0 and d["peak_voltage"] <= 12.0
    assert max(abs(v) for v in ref["voltage"]) <= 12.0 + 1e-9
    assert len(ref["t"]) == math.floor(d["period"] * 200) + 1


@pytest.mark.parametrize(("body", "field"), [
    ({"amplitude": 0, "period": 2, "q": 2}, "amplitude"),
    ({"amplitude": 0.5, "period": -1, "q": 2}, "period"),
    ({"amplitude": 0.5, "period": 2, "q": 99}, "q"),
    ({"amplitude": 0.5, "period": 2, "q": 2, "bogus": 1}, "bogus"),
    ({"amplitude": 0.5, "period": 2, "q": 2, "params": "/etc/passwd"}, "params"),
    ({"amplitude": 0.5, "period": 2, "q": 2, "params": {"J": 1.0}}, "params.B"),
    ({"amplitude": 0.5, "period": 2000, "q": 2}, "rate"),
    ({"amplitude": 0.5, "period": 2, "q": 2, "rate": "fast"}, "rate"),
    ({"amplitude": 100.0, "limits": {"current": 2.0, "voltage": 12.0}}, "amplitude"),
    ({"amplitude": 0.3, "period": 2.0, "limits": {"current": 2.0, "voltage": 12.0}}, "body"),
])
def test_analytic_rejects_bad_input_naming_the_field(http: httpx.Client, body: dict[str, object],
                                                     field: str) -> None:
    p = problem(http.post("/v1/references/analytic", json=body), 422)
    assert p["field"] == field, p
    assert p["reason"]


def test_invalid_json_and_unknown_routes(http: httpx.Client) -> None:
    p = problem(http.post("/v1/references/analytic", content=b"{bad", headers={"content-type": "application/json"}),
                422)
    assert p["field"] == "body" and "JSON" in str(p["reason"])
    problem(http.get("/v1/nope"), 404)
    problem(http.get("/v1/references/analytic"), 405)


def test_body_limit_413(http: httpx.Client) -> None:
    big = {"missions": [mission("m", profile=None)], "pad": "x" * (BODY_LIMIT + 10)}
    p = problem(http.post("/v1/batches", json=big), 413)
    assert p["field"] == "body"

    def chunks() -> Iterator[bytes]:  # no Content-Length: the limit is enforced while reading
        yield b'{"missions": ['
        for _ in range(BODY_LIMIT // 1000 + 2):
            yield b" " * 1000
        yield b"]}"

    problem(http.post("/v1/batches", content=chunks(), headers={"content-type": "application/json"}), 413)
    assert http.get("/healthz").status_code == 200


def test_batch_lifecycle_json_and_csv(http: httpx.Client) -> None:
    missions = [mission(f"m{i}", amplitude=0.1 + 0.05 * i) for i in range(4)]
    r = http.post("/v1/batches", json={"missions": missions})
    assert r.status_code == 202, r.text
    acc = r.json()
    assert acc["status"] in ("queued", "running") and r.headers["location"] == f"/v1/batches/{acc['id']}"
    status = _wait(http, acc["id"])
    assert status["status"] == "done" and status["counts"]["done"] == 4 and status["progress"] == 1.0
    res = http.get(f"/v1/batches/{acc['id']}/results").json()
    assert [it["name"] for it in res["results"]] == ["m0", "m1", "m2", "m3"]
    assert all(it["status"] == "done" and it["result"]["name"] == it["name"] for it in res["results"])
    csv_text = http.get(f"/v1/batches/{acc['id']}/results", params={"format": "csv"}).text
    lines = csv_text.strip().splitlines()
    assert lines[0].startswith("index,name,status") and len(lines) == 5 and lines[1].startswith("0,m0,done")
    via_accept = http.get(f"/v1/batches/{acc['id']}/results", headers={"accept": "text/csv"})
    assert via_accept.headers["content-type"].startswith("text/csv") and via_accept.text == csv_text


def _wait(http: httpx.Client, batch_id: str, timeout: float = 60.0) -> dict[str, Any]:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        s = http.get(f"/v1/batches/{batch_id}").json()
        if s["status"] in ("done", "failed"):
            return s
        time.sleep(0.1)
    raise AssertionError(f"batch {batch_id} not finished in {timeout} s")


def test_batch_idempotency(http: httpx.Client) -> None:
    body = {"missions": [mission("idem-a"), mission("idem-b")]}
    key = f"key-{time.time_ns()}"
    first = http.post("/v1/batches", json=body, headers={"Idempotency-Key": key})
    again = http.post("/v1/batches", json=body, headers={"Idempotency-Key": key})
    assert first.status_code == again.status_code == 202
    assert first.json()["id"] == again.json()["id"] and again.headers["idempotent-replayed"] == "true"
    other = {"missions": [mission("idem-c")]}
    p = problem(http.post("/v1/batches", json=other, headers={"Idempotency-Key": key}), 422)
    assert p["field"] == "Idempotency-Key"
    _wait(http, first.json()["id"])
    assert len(http.get(f"/v1/batches/{first.json()['id']}/results").json()["results"]) == 2


def test_batch_failures(http: httpx.Client) -> None:
    problem(http.get("/v1/batches/doesnotexist"), 404)
    problem(http.get("/v1/batches/doesnotexist/results"), 404)
    p = problem(http.post("/v1/batches", json={"missions": [mission(f"x{i}") for i in range(6)]}), 413)
    assert p["field"] == "missions"
    p = problem(http.post("/v1/batches", json={"missions": []}), 422)
    assert p["field"] == "missions"
    p = problem(http.post("/v1/batches", json={"missions": [mission("ok"), mission("bad", regularity="smooth")]}),
                422)
    assert p["field"] == "missions.1.regularity"
    p = problem(http.post("/v1/batches", json={"missions": [mission("big", collocation={"intervals": 500})]}), 422)
    assert p["field"] == "missions.0.collocation.intervals"
    long = {"name": "long", "profile": {"t": [i * 0.001 for i in range(6000)], "thrust": [0.1] * 6000}}
    p = problem(http.post("/v1/batches", json={"missions": [long]}), 422)
    assert p["field"] == "missions.0.profile.t"
    p = problem(http.post("/v1/batches", json={"missions": [mission("p", params="../../etc/passwd")]}), 422)
    assert p["field"] == "missions.0.params"
    p = problem(http.post("/v1/batches", json={"missions": [mission("x")]}, headers={"Idempotency-Key": ""}), 422)
    assert p["field"] == "Idempotency-Key"


needs_optimize = pytest.mark.skipif(available_tasks().optimize is None, reason="ocp.optimize.solve is not installed")
needs_compare = pytest.mark.skipif(available_tasks().compare is None, reason="ocp.optimize.compare is not installed")


@needs_optimize
@pytest.mark.slow
def test_optimize_route(http: httpx.Client) -> None:
    r = http.post("/v1/references/optimize", json=mission("opt", collocation={"intervals": 60}))
    assert r.status_code == 200, r.text
    out = r.json()
    assert out["source"] in ("optimized", "analytic-fallback")
    assert len(out["t"]) == len(out["voltage"]) > 2
    assert out["verification"]["max_abs_voltage"] <= 12.0 + 1e-6
    p = problem(http.post("/v1/references/optimize", json=mission("bad", limits={"voltage": -1})), 422)
    assert p["field"] == "limits.voltage"
    p = problem(http.post("/v1/references/optimize", json=mission("big", collocation={"intervals": 301})), 422)
    assert p["field"] == "collocation.intervals"
    # a 10 nH winding cannot be verified within the step budget: a clear 422, the worker lives on
    stiff = {"J": 2.71e-5, "B": 5.31e-5, "c_tau": 2.2e-6, "c_f": 1.4e-4, "k_t": 0.0573, "k_e": 0.0573, "R": 5.0,
             "L": 1e-8}
    p = problem(http.post("/v1/references/optimize", json=mission("stiff", params=stiff)), 422)
    assert p["field"] == "params" and "too stiff" in p["detail"]
    assert http.post("/v1/references/optimize", json=mission("again", collocation={"intervals": 60})).status_code == 200


@needs_compare
@pytest.mark.slow
def test_compare_route(http: httpx.Client) -> None:
    r = http.post("/v1/compare", json=mission("cmp", collocation={"intervals": 60}))
    assert r.status_code == 200, r.text
    assert isinstance(r.json(), dict) and r.json()
    p = problem(http.post("/v1/compare", json={"name": "cmp"}), 422)
    assert p["field"] in ("body", "profile", "segments")
