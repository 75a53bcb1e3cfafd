"""The server's log, read from a real uvicorn process: a ``start`` line, the "resuming batch items"
line under uvicorn's logging config, one request line and one structured task line per task (id,
kind, duration, outcome) carrying the request's ``X-Request-ID``, a timed-out task's outcome, and
``stop``."""

from __future__ import annotations

import re
import subprocess
import sys
import time
from pathlib import Path

import httpx
import pytest

from service.jobs import JobStore
from service.tasks import available_tasks
from tests.service.test_service_support import ROOT, mission, running_server

SIN = {"params": "paper-rig", "amplitude": 0.5, "period": 2.0, "q": 2, "rate": 100.0}


def lines(text: str, *parts: str) -> list[str]:
    return [line for line in text.splitlines() if all(p in line for p in parts)]


@pytest.mark.integration
@pytest.mark.skipif(available_tasks().fallback is None, reason="ocp.optimize.solve is not installed")
def test_server_logs_start_resume_requests_tasks_timeouts(tmp_path: Path) -> None:
    db = tmp_path / "jobs.db"
    store = JobStore(db)  # a batch item a killed server left running
    batch_id, _ = store.create_batch([mission("left-running")], None)
    assert len(store.claim(1)) == 1
    store.close()
    env = {"TS_TEST_TASKS": "hang-optimize", "THRUSTSHAPE_DB_PATH": str(db), "TS_TEST_ITEM_SECONDS": "0.05",
           "THRUSTSHAPE_OPTIMIZE_DEADLINE_S": "2", "THRUSTSHAPE_FALLBACK_RESERVE_S": "1"}
    with running_server(tmp_path, env, warm=True) as srv, httpx.Client(base_url=srv.url, timeout=60) as http:
        ok = http.post("/v1/references/analytic", json=SIN, headers={"X-Request-ID": "tour-1"})
        assert ok.status_code == 200 and ok.headers["x-request-id"] == "tour-1"
        bad = http.post("/v1/references/analytic", json={**SIN, "q": -1})
        assert bad.status_code == 422
        slow = http.post("/v1/references/optimize", json=mission("hangs"), headers={"X-Request-ID": "hang-2"})
        assert slow.status_code == 200 and slow.json()["source"] == "analytic-fallback"  # the solver timed out
        end = time.monotonic() + 30
        while http.get(f"/v1/batches/{batch_id}").json()["status"] != "done" and time.monotonic() < end:
            time.sleep(0.1)
    text = srv.log.read_text()
    assert re.search(r"thrustshape\.service: resuming 1 batch items .* request_id=-", text), text
    assert re.search(r"thrustshape\.service: start version=\S+ workers=1 queue=\d+ db=\S+jobs\.db "
                     r"batch_backend=local", text), text
    [task] = lines(text, "thrustshape.tasks: task ", "request_id=tour-1")
    assert re.search(r"task id=[0-9a-f]{12} kind=analytic duration_ms=\d+\.\d outcome=ok request_id=tour-1$", task)
    assert lines(text, "thrustshape.http: request method=POST path=/v1/references/analytic status=200",
                 "request_id=tour-1")
    assert lines(text, "status=422", "request_id=" + bad.headers["x-request-id"])
    [timeout] = lines(text, "thrustshape.tasks: task ", "kind=optimize", "request_id=hang-2")
    assert "WARNING" in timeout and "outcome=timeout error=TaskTimeout" in timeout
    [fallback] = lines(text, "thrustshape.tasks: task ", "kind=fallback", "request_id=hang-2")  # what answered
    assert "outcome=ok" in fallback
    # the pool's own kill/replace lines carry the request id; the killed solver is one of them
    assert lines(text, "thrustshape.workers", "request_id=hang-2")
    worker_lines = lines(text, "thrustshape.workers")
    assert all("request_id=" in line for line in worker_lines)
    assert lines(text, "thrustshape.service: stop request_id=-")


def test_serve_logging_config_keeps_the_app_loggers_with_request_ids() -> None:
    """``thrustshape serve`` hands uvicorn :func:`log_config`: thrustshape.* INFO lines are printed (with the
    request id) even when uvicorn's own level is warning; uvicorn's access lines carry the request id."""
    code = ("import logging, logging.config\n"
            "from service.api.logging import log_config, request_id\n"
            "request_id.set('r-42')\n"
            "logging.config.dictConfig(log_config('info'))\n"
            "logging.getLogger('uvicorn.access').info('%s - \"%s %s HTTP/%s\" %d', '127.0.0.1:5', 'GET', '/healthz',"
            " '1.1', 200)\n"  # the call uvicorn's protocol makes
            "logging.config.dictConfig(log_config('warning'))\n"
            "logging.getLogger('thrustshape.service').info('resuming 3 batch items left running')\n"
            "logging.getLogger('uvicorn.error').info('uvicorn chatter')\n"
            "logging.getLogger('uvicorn.error').warning('uvicorn warning')\n")
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert "Traceback" not in run.stderr and "Logging error" not in run.stderr, run.stderr
    assert re.search(r'INFO uvicorn\.access: 127\.0\.0\.1:5 - "GET /healthz HTTP/1\.1" 200 OK request_id=r-42$',
                     run.stderr, re.M), run.stderr
    assert re.search(r"INFO thrustshape\.service: resuming 3 batch items left running request_id=r-42$",
                     run.stderr, re.M), run.stderr
    assert "uvicorn chatter" not in run.stderr and "uvicorn warning request_id=r-42" in run.stderr
