"""The HTTP client (in-process through an injected ASGI transport, and against a real server), its
error tree and 503 retry policy, and the ``serve`` / ``batch`` commands."""

from __future__ import annotations

import asyncio
import csv
import json
import time
from pathlib import Path
from typing import Any

import httpx
import pytest

from clients import (
    AsyncClient,
    BadRequest,
    Client,
    ClientError,
    InvalidInput,
    NotFound,
    ServerBusy,
    Timeout,
    TransportError,
    Unauthorized,
)
from clients.cli import main
from service.app import create_app
from service.settings import Settings
from service.tasks import TaskSet, available_tasks
from tests.service.test_service_support import free_port, mission, running_server, slow_item


def test_async_client_in_process(tmp_path: Path) -> None:
    app = create_app(Settings(db_path=tmp_path / "jobs.db", workers=1), tasks=TaskSet(batch_item=slow_item))

    async def scenario() -> None:
        async with app.router.lifespan_context(app):
            transport = httpx.ASGITransport(app=app)
            async with AsyncClient("http://thrustshape.test", transport=transport) as c:
                assert (await c.health())["status"] == "ok"
                assert (await c.info())["features"]["batches"] is True
                ref = await c.analytic({"amplitude": 0.4, "period": 1.0, "q": 1, "rate": 50})
                assert len(ref["t"]) == 51 and ref["thrust"][0] == 0.0
                with pytest.raises(InvalidInput) as bad:
                    await c.analytic({"amplitude": 0.4, "period": 1.0, "q": -1})
                assert bad.value.field == "q" and bad.value.status == 422
                assert isinstance(bad.value, ValueError) and isinstance(bad.value, ClientError)
                with pytest.raises(NotFound):
                    await c.batch("nope")
                acc = await c.submit_batch([mission("a"), mission("b")], idempotency_key="k1")
                assert (await c.submit_batch([mission("a"), mission("b")], idempotency_key="k1"))["id"] == acc["id"]
                final = await c.wait_batch(acc["id"], poll=0.05, timeout=60)
                assert final["status"] == "done" and final["counts"]["done"] == 2
                res = await c.batch_results(acc["id"])
                assert [r["name"] for r in res["results"]] == ["a", "b"]
                assert (await c.batch_results_csv(acc["id"])).startswith("index,name,status")

    asyncio.run(scenario())


def test_retries_503_honouring_retry_after() -> None:
    calls: list[float] = []

    def handler(request: httpx.Request) -> httpx.Response:
        calls.append(time.monotonic())
        if len(calls) < 3:
            return httpx.Response(503, headers={"Retry-After": "0.3"}, json={"title": "Server busy", "status": 503})
        return httpx.Response(200, json={"status": "ok"})

    with Client("http://x", transport=httpx.MockTransport(handler), retries=3) as c:
        assert c.health()["status"] == "ok"
    assert len(calls) == 3
    assert calls[1] - calls[0] >= 0.3 and calls[2] - calls[1] >= 0.3

    calls.clear()
    with Client("http://x", transport=httpx.MockTransport(lambda r: httpx.Response(
            503, headers={"Retry-After": "0"}, json={"title": "Server busy", "detail": "full"})), retries=2) as c, \
            pytest.raises(ServerBusy) as busy:
        c.info()
    assert busy.value.retry_after == 0.0 and busy.value.status == 503


def test_transport_errors_are_typed() -> None:
    def slow(request: httpx.Request) -> httpx.Response:
        raise httpx.ReadTimeout("too slow", request=request)

    with Client("http://x", transport=httpx.MockTransport(slow)) as c, pytest.raises(Timeout):
        c.health()
    with Client(f"http://127.0.0.1:{free_port()}", timeout=2.0) as c, pytest.raises(TransportError):
        c.health()  # nobody listens there


@pytest.mark.integration
def test_api_key_guards_everything_but_healthz(tmp_path: Path) -> None:
    env = {"THRUSTSHAPE_DB_PATH": str(tmp_path / "jobs.db"), "THRUSTSHAPE_API_KEY": "s3cret"}
    with running_server(tmp_path, env, factory=False) as srv:  # the real `thrustshape serve`
        with Client(srv.url) as anon:
            assert anon.health()["status"] == "ok"
            with pytest.raises(Unauthorized) as err:
                anon.info()
            assert err.value.headers["www-authenticate"] == "Bearer"
        assert httpx.get(f"{srv.url}/openapi.json").status_code == 401
        assert httpx.get(f"{srv.url}/docs").status_code == 401
        with Client(srv.url, api_key="wrong") as bad, pytest.raises(Unauthorized):
            bad.analytic({"amplitude": 0.4, "period": 1.0, "q": 1})
        with Client(srv.url, api_key="s3cret") as good:
            info = good.info()
            assert info["workers"] == 1
            assert info["features"]["optimize"] is (available_tasks().optimize is not None)
            assert len(good.analytic({"amplitude": 0.4, "period": 1.0, "q": 1, "rate": 20})["t"]) == 21
            with pytest.raises(BadRequest) as bad_req:
                good.analytic({"amplitude": 0.4, "q": 1})
            assert bad_req.value.field == "period"
        spec = httpx.get(f"{srv.url}/openapi.json", headers={"Authorization": "Bearer s3cret"}).json()
        assert "HTTPBearer" in spec["components"]["securitySchemes"]


def _write_missions(d: Path, n: int, **extra: Any) -> Path:
    d.mkdir()
    for i in range(n):
        (d / f"m{i}.json").write_text(json.dumps(mission(f"cli{i}", amplitude=0.2 + 0.05 * i, **extra)))
    return d


@pytest.mark.integration
def test_cli_batch_against_server(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = _write_missions(tmp_path / "missions", 3)
    env = {"THRUSTSHAPE_DB_PATH": str(tmp_path / "jobs.db"), "TS_TEST_TASKS": "slow-batch",
           "TS_TEST_ITEM_SECONDS": "0.05"}
    with running_server(tmp_path, env) as srv:
        code = main(["batch", str(src), "--server", srv.url, "--out", str(tmp_path / "out")])
    out = capsys.readouterr()
    assert code == 0, out.err
    assert "3/3 done=3 failed=0" in out.err  # the progress bar's last state
    assert "3 done, 0 failed" in out.out and "cli0" in out.out
    rows = list(csv.DictReader((tmp_path / "out" / "summary.csv").read_text().splitlines()))
    assert [r["name"] for r in rows] == ["cli0", "cli1", "cli2"] and {r["status"] for r in rows} == {"done"}
    assert json.loads((tmp_path / "out" / "0001-cli1.json").read_text())["result"]["name"] == "cli1"


def test_cli_batch_rejects_bad_missions(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    d = tmp_path / "bad"
    d.mkdir()
    (d / "a.json").write_text(json.dumps(mission("x", regularity="smooth")))
    assert main(["batch", str(d), "--local"]) == 1
    assert "a.json: regularity" in capsys.readouterr().err
    assert main(["batch", str(tmp_path / "missing.json")]) == 1
    with pytest.raises(SystemExit):  # usage error: --server and --local together
        main(["batch", str(d), "--server", "http://x", "--local"])
    assert main(["batch", str(d / "a.json"), "--server", f"http://127.0.0.1:{free_port()}"]) == 1


@pytest.mark.slow
@pytest.mark.skipif(available_tasks().optimize is None, reason="ocp.optimize.solve is not installed")
def test_cli_batch_local_optimises(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    src = _write_missions(tmp_path / "missions", 2, collocation={"intervals": 40})
    code = main(["batch", str(src), "--local", "--workers", "1", "--json"])
    out = capsys.readouterr()
    assert code == 0, out.err
    summary = json.loads(out.out)["summary"]
    assert [r["name"] for r in summary] == ["cli0", "cli1"]
    assert all(r["source"] in ("optimized", "analytic-fallback") for r in summary)
    assert all(r["max_abs_voltage"] <= 12.0 + 1e-6 for r in summary)
