"""Model checks as jobs over real HTTP (a uvicorn subprocess, one worker process, a real SQLite file): a
diagnosis that overruns the synchronous route's task timeout completes as a job with progress; the CLI's
``--server`` diagnose uses the job and forwards every option the local command takes (the same verdicts as
a local run); failed jobs answer their problem naming the field; the experiment design runs as a job; a job
a killed server left unfinished runs after the restart."""

from __future__ import annotations

import json
import sqlite3
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import pytest

from clients.cli import main
from clients.client import Client, InvalidInput
from ocp.logs import Log, write_log_csv
from ocp.model.params import MotorParams
from tests.service.test_service_support import Server, problem, start_server
from tests.synthetic_rig import RigSpec, generate

pytestmark = pytest.mark.integration

JOBS = "/v1/model-check/jobs"
ENV = {"TS_TEST_TASKS": "slow-batch", "THRUSTSHAPE_TASK_TIMEOUT_S": "0.5", "OPENBLAS_NUM_THREADS": "1"}


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("model-check-jobs")
    srv = start_server(tmp, {**ENV, "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db")})
    yield srv
    srv.stop()


def _csv(log: Log, tmp: Path, name: str) -> Path:
    path = tmp / name
    write_log_csv(log, path)
    return path


@pytest.fixture(scope="module")
def friction_csv(rig: MotorParams, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """3 s at 1 kHz with a Coulomb friction the model lacks (diagnose takes ~1.5 s: over the 0.5 s timeout)."""
    log = generate(rig, RigSpec(effects={"coulomb_friction": {"tau_c": 0.003}}, seconds=1.0, seed=1))
    return _csv(log, tmp_path_factory.mktemp("csv"), "friction.csv")


def _poll(http: httpx.Client, job_id: str, timeout: float = 120.0) -> list[dict[str, Any]]:
    seen, end = [], time.monotonic() + timeout
    while time.monotonic() < end:
        seen.append(http.get(f"{JOBS}/{job_id}").json())
        if seen[-1]["status"] in ("done", "failed"):
            return seen
        time.sleep(0.05)
    raise AssertionError(f"job {job_id} did not finish: {seen[-1]}")


def test_a_diagnosis_past_the_request_timeout_completes_as_a_job(http: httpx.Client, friction_csv: Path) -> None:
    files = {"log": ("friction.csv", friction_csv.read_bytes())}
    problem(http.post("/v1/model-check/diagnose", files=files, data={"params": "paper-rig"}), 504)
    r = http.post(JOBS, files=files, data={"params": "paper-rig", "op": "diagnose"})
    assert r.status_code == 202, r.text[:300]
    job = r.json()
    assert job["status"] in ("queued", "running") and r.headers["location"] == f"{JOBS}/{job['id']}"
    if http.get(f"{JOBS}/{job['id']}").json()["status"] != "done":
        assert problem(http.get(f"{JOBS}/{job['id']}/result"), 409)["title"] == "Not finished"
    seen = _poll(http, job["id"])
    assert seen[-1]["status"] == "done" and seen[-1]["progress"] == 1.0
    progress = [float(s["progress"]) for s in seen]
    assert any(0.0 < p < 1.0 for p in progress), progress  # the worker reported progress while it ran
    assert progress == sorted(progress)
    assert http.get(f"{JOBS}/{job['id']}/result").json()["verdict"] == ["coulomb_friction"]
    problem(http.get(f"{JOBS}/nope"), 404)
    spec = http.get("/openapi.json").json()
    assert "multipart/form-data" in spec["paths"][JOBS]["post"]["requestBody"]["content"]
    assert spec["paths"][JOBS]["post"]["operationId"]


def test_a_failed_job_answers_its_problem_naming_the_field(http: httpx.Client, friction_csv: Path) -> None:
    r = http.post(JOBS, files={"log": ("broken.csv", b"t,voltage\n0,\x00\xff\xfe\n")}, data={"params": "paper-rig"})
    assert r.status_code == 202
    seen = _poll(http, r.json()["id"])
    assert seen[-1]["status"] == "failed" and seen[-1]["error"]["field"] == "omega"
    body = problem(http.get(f"{JOBS}/{r.json()['id']}/result"), 422)  # a column of the log: shown next to it
    assert body["field"] == "omega" and body["form_field"] == "log" and "missing" in body["reason"]
    # bad form fields are refused before anything is stored
    for form, field in (({"op": "fit"}, "effects"), ({"op": "design", "rivals": "coulomb_friction"}, "rivals"),
                        ({"tolerance": "2"}, "tolerance"), ({"max_logging_skew": "-1"}, "max_logging_skew")):
        got = problem(http.post(JOBS, files={"log": ("f.csv", friction_csv.read_bytes())},
                                data={"params": "paper-rig", **form}), 422)
        assert got["field"] == field, got


@pytest.mark.parametrize(("error", "args"), [(0.05, ["--tolerance", "0.02"]), (0.05, [])])
def test_server_diagnose_forwards_the_tolerance(error: float, args: list[str], rig: MotorParams, server: Server,
                                                tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """True R is 5 % above nominal: named only with --tolerance 0.02; locally and on the server alike."""
    csv = _csv(generate(rig, RigSpec(seconds=1.0, seed=7)), tmp_path, "r.csv")
    params = tmp_path / "p.json"
    params.write_text(json.dumps({**rig.model_dump(), "R": rig.R / (1 + error)}))
    verdicts = []
    for where in ([], ["--server", server.url]):
        assert main(["diagnose", str(csv), "--params", str(params), "--json", *args, *where]) == 0
        verdicts.append(json.loads(capsys.readouterr().out)["verdict"])
    assert verdicts[0] == verdicts[1] == (["param:R"] if args else [])


def test_server_diagnose_forwards_the_logging_skew(rig: MotorParams, server: Server, tmp_path: Path,
                                                   capsys: pytest.CaptureFixture[str]) -> None:
    """A command logged 4 rows early: an input delay beyond the default 2-sample skew, a logging convention
    within --max-logging-skew 5."""
    log = generate(rig, RigSpec(seconds=1.0, seed=6))
    v = np.concatenate([log.voltage[4:], np.repeat(log.voltage[-1], 4)])
    csv = _csv(Log(log.t, v, log.current, log.omega, log.theta, log.thrust, log.kind, log.source), tmp_path, "s.csv")
    for args, delay in (([], True), (["--max-logging-skew", "5"], False)):
        out = []
        for where in ([], ["--server", server.url]):
            assert main(["diagnose", str(csv), "--params", "paper-rig", "--json", *args, *where]) == 0
            out.append(json.loads(capsys.readouterr().out))
        assert out[0]["verdict"] == out[1]["verdict"] == (["input_delay"] if delay else [])
        assert out[0]["alignment"] == out[1]["alignment"] and out[1]["alignment"]["called_input_delay"] is delay


def test_design_runs_as_a_job(server: Server, friction_csv: Path) -> None:
    with Client(server.url) as c:
        seen: list[float] = []
        d = c.design_experiment(str(friction_csv), "paper-rig", rivals=[["coulomb_friction"], ["param:B"]],
                                voltage=12.0, current=1.0, duration_s=1.5, on_progress=seen.append, timeout=240)
        assert d["needed"] and [r["items"] for r in d["rivals"]] == [["coulomb_friction"], ["param:B"]]
        assert d["mission"] is not None and d["verification"]["max_abs_current"] <= 1.0 + 1e-6
        assert d["separation"] > 0 and d["diagnosis"]["verdict"] == ["coulomb_friction"]
        assert seen[-1] == 1.0
        with pytest.raises(InvalidInput) as exc:
            c.design_experiment(str(friction_csv), "paper-rig", rivals="coulomb_friction;nope")
        assert exc.value.field == "rivals"


def test_an_unfinished_job_runs_after_a_restart(tmp_path: Path, friction_csv: Path) -> None:
    db = tmp_path / "jobs.db"
    srv = start_server(tmp_path, {**ENV, "THRUSTSHAPE_DB_PATH": str(db)})
    try:
        r = httpx.post(srv.url + JOBS, files={"log": ("f.csv", friction_csv.read_bytes())},
                       data={"params": "paper-rig"}, timeout=30)
        assert r.status_code == 202
        srv.kill()  # SIGKILL before the worker (still starting) could finish it
    finally:
        srv.stop()
    with sqlite3.connect(db) as con:  # stored, not finished
        state = con.execute("SELECT state FROM model_checks WHERE id = ?", (r.json()["id"],)).fetchone()[0]
    assert state in ("queued", "running")
    srv = start_server(tmp_path, {**ENV, "THRUSTSHAPE_DB_PATH": str(db)})
    try:
        with httpx.Client(base_url=srv.url, timeout=30) as http:
            seen = _poll(http, r.json()["id"])
            assert seen[-1]["status"] == "done" and seen[-1]["attempts"] >= 1
            assert http.get(f"{JOBS}/{r.json()['id']}/result").json()["verdict"] == ["coulomb_friction"]
    finally:
        srv.stop()
