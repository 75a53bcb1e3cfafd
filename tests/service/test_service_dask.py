"""Batches on a real Dask ``LocalCluster`` give the same results as on local worker processes.

The cluster runs in the test process (``processes=False``, one worker thread: 2-core machine); the
server is a real uvicorn subprocess that reaches the scheduler over TCP. Items are real optimiser
runs (``ocp.optimize.solve``).
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import pytest

from service.tasks import available_tasks
from tests.service.test_service_support import mission, running_server

pytestmark = [pytest.mark.integration, pytest.mark.slow,
              pytest.mark.skipif(available_tasks().batch_item is None, reason="ocp.optimize.solve is not installed")]

#: fields that legitimately differ between two runs of the same solve
VOLATILE = {"solve_time_s", "total_time_s", "build_time_s", "solver"}


@pytest.fixture(scope="module")
def cluster() -> Iterator[Any]:
    from distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None,
                      scheduler_port=0, host="127.0.0.1", protocol="tcp") as c:
        yield c


def _run_batch(url: str, missions: list[dict[str, Any]]) -> list[dict[str, Any]]:
    batch_id = httpx.post(f"{url}/v1/batches", json={"missions": missions}, timeout=30).json()["id"]
    end = time.monotonic() + 120
    while httpx.get(f"{url}/v1/batches/{batch_id}", timeout=10).json()["status"] not in ("done", "failed"):
        assert time.monotonic() < end, "batch did not finish"
        time.sleep(0.2)
    return httpx.get(f"{url}/v1/batches/{batch_id}/results", timeout=30).json()["results"]


def _stable(obj: Any) -> Any:
    if isinstance(obj, dict):
        return {k: _stable(v) for k, v in obj.items() if k not in VOLATILE}
    if isinstance(obj, list):
        return [_stable(v) for v in obj]
    return obj


def _close(a: Any, b: Any, path: str = "") -> None:
    """Same structure; numbers equal to 1e-9 relative (same code, same inputs: same IPOPT iterates)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), path
        for k in a:
            _close(a[k], b[k], f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            _close(x, y, f"{path}[{i}]")
    elif isinstance(a, float) and isinstance(b, float):
        assert b == pytest.approx(a, rel=1e-9, abs=1e-12), path
    else:
        assert a == b, path


def test_dask_batch_matches_local_batch(cluster: Any, tmp_path: Path) -> None:
    missions = [mission(f"d{i}", amplitude=0.2 + 0.05 * i, collocation={"intervals": 40}) for i in range(3)]
    missions.append(mission("bad-amplitude", amplitude=50.0, collocation={"intervals": 40}))
    with running_server(tmp_path, {"THRUSTSHAPE_DB_PATH": str(tmp_path / "local.db")}) as local:
        local_res = _run_batch(local.url, missions)
    env = {"THRUSTSHAPE_DB_PATH": str(tmp_path / "dask.db"), "THRUSTSHAPE_DASK_ADDRESS": cluster.scheduler_address}
    with running_server(tmp_path, env) as remote:
        assert httpx.get(f"{remote.url}/v1/info", timeout=10).json()["batch_backend"] == "dask"
        dask_res = _run_batch(remote.url, missions)
    assert [r["name"] for r in dask_res] == [m["name"] for m in missions]
    assert [r["status"] for r in dask_res] == [r["status"] for r in local_res]
    assert sum(r["status"] == "done" for r in dask_res) >= 3
    for a, b in zip(local_res, dask_res, strict=True):
        _close(_stable(a["result"]), _stable(b["result"]), a["name"])
        _close(_stable(a["error"]), _stable(b["error"]), a["name"])
