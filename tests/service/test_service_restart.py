"""Crash safety: a real uvicorn server with a real SQLite file is SIGKILLed in the middle of a batch;
a new server on the same file finishes it with every item exactly once and no stored result changed."""

from __future__ import annotations

import sqlite3
import time
from pathlib import Path
from typing import Any

import httpx
import pytest

from service.schemas import MissionRequest
from tests.service.test_service_support import digest, mission, start_server

pytestmark = [pytest.mark.integration, pytest.mark.slow]

N = 10


def _results(url: str, batch_id: str) -> dict[str, Any]:
    return httpx.get(f"{url}/v1/batches/{batch_id}/results", timeout=10).json()


def test_sigkill_mid_batch_then_restart_completes_exactly_once(tmp_path: Path) -> None:
    db = tmp_path / "jobs.sqlite3"
    env = {"TS_TEST_TASKS": "slow-batch", "TS_TEST_ITEM_SECONDS": "0.4", "THRUSTSHAPE_DB_PATH": str(db)}
    missions = [mission(f"k{i}", amplitude=0.1 + 0.01 * i) for i in range(N)]
    expected = [digest(MissionRequest.model_validate(m).model_dump(mode="json")) for m in missions]

    first = start_server(tmp_path, env)
    try:
        r = httpx.post(f"{first.url}/v1/batches", json={"missions": missions}, timeout=10,
                       headers={"Idempotency-Key": "restart-test"})
        assert r.status_code == 202
        batch_id = r.json()["id"]
        end = time.monotonic() + 60
        while httpx.get(f"{first.url}/v1/batches/{batch_id}", timeout=10).json()["counts"]["done"] < 3:
            assert time.monotonic() < end, "batch made no progress"
            time.sleep(0.05)
        snapshot = _results(first.url, batch_id)["results"]
        before = {it["index"]: it["result"] for it in snapshot if it["status"] == "done"}
    finally:
        first.kill()
    assert 3 <= len(before) < N, f"kill came too late to be mid-batch ({len(before)} of {N} done)"

    with sqlite3.connect(db) as con:  # what the dead server left behind, read from the file itself
        states = dict(con.execute("SELECT idx, state FROM items WHERE batch_id = ?", (batch_id,)).fetchall())
    interrupted = [i for i, s in states.items() if s == "running"]
    assert all(states[i] == "done" for i in before)
    assert sum(s == "queued" for s in states.values()) >= 1

    second = start_server(tmp_path, env)
    try:
        # resubmitting after the crash (same key) must not create a second batch
        again = httpx.post(f"{second.url}/v1/batches", json={"missions": missions}, timeout=10,
                           headers={"Idempotency-Key": "restart-test"})
        assert again.json()["id"] == batch_id
        end = time.monotonic() + 90
        while httpx.get(f"{second.url}/v1/batches/{batch_id}", timeout=10).json()["status"] != "done":
            assert time.monotonic() < end, "batch not finished after restart"
            time.sleep(0.1)
        res = _results(second.url, batch_id)["results"]
    finally:
        second.stop()

    assert [it["index"] for it in res] == list(range(N))  # each item exactly once, in order
    assert all(it["status"] == "done" for it in res)
    assert [it["result"]["digest"] for it in res] == expected  # each result belongs to its own mission
    assert [it["name"] for it in res] == [m["name"] for m in missions]
    for i, result in before.items():  # finished before the kill: untouched, not recomputed
        assert res[i]["result"] == result
    for i in interrupted:  # running at the kill: resumed, counted as a second attempt
        assert res[i]["attempts"] == 2
    with sqlite3.connect(db) as con:
        assert con.execute("SELECT COUNT(*) FROM batches").fetchone()[0] == 1
        assert con.execute("SELECT COUNT(*) FROM items").fetchone()[0] == N
