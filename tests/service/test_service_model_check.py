"""The model-check routes over real HTTP (a uvicorn subprocess, one worker process): a synthetic-rig log
with a hidden Coulomb friction is checked (JSON and HTML), diagnosed (friction named) and fitted (the
calibrated parameters load and fit the log to the sensor noise); bad uploads get problem+json naming
the form field or the log column."""

from __future__ import annotations

import io
import json
import zipfile
from collections.abc import Callable, Iterator
from pathlib import Path

import httpx
import numpy as np
import pyarrow as pa
import pyarrow.parquet as pq
import pytest
import scipy.io as sio

from ocp.logs import Log, write_log_csv
from ocp.model.effects import CATALOGUE, load_plant
from ocp.model.params import MotorParams
from tests.service.test_service_support import Server, problem, start_server
from tests.synthetic_rig import RigSpec, generate

pytestmark = pytest.mark.integration

UPLOAD_LIMIT = 300_000
LOG_ROWS_LIMIT = 4_000
TAU_C = 0.003  # hidden Coulomb friction [N m]
CHECK = "/v1/model-check/check"


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("model-check")
    srv = start_server(tmp, {"TS_TEST_TASKS": "slow-batch", "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"),
                             "THRUSTSHAPE_MAX_UPLOAD_BYTES": str(UPLOAD_LIMIT),
                             "THRUSTSHAPE_MAX_LOG_SAMPLES": str(LOG_ROWS_LIMIT), "OPENBLAS_NUM_THREADS": "1"})
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def rig_log(rig: MotorParams) -> Log:
    """3 s at 1 kHz (sine, sin^5, chirp; 1 s each) from a rig with a friction the model lacks."""
    return generate(rig, RigSpec(effects={"coulomb_friction": {"tau_c": TAU_C}}, seconds=1.0, seed=1))


@pytest.fixture(scope="module")
def rig_csv(rig_log: Log, tmp_path_factory: pytest.TempPathFactory) -> bytes:
    path = tmp_path_factory.mktemp("csv") / "rig.csv"
    write_log_csv(rig_log, path)
    data = path.read_bytes()
    assert len(data) < UPLOAD_LIMIT
    return data


def post(http: httpx.Client, path: str, log: tuple[str, bytes] | None, **form: str) -> httpx.Response:
    return http.post(path, files={"log": log} if log is not None else None, data={"params": "paper-rig", **form})


def test_info_lists_the_catalogue_and_the_feature(http: httpx.Client) -> None:
    info = http.get("/v1/info").json()
    assert info["effects"] == sorted(CATALOGUE) and "coulomb_friction" in info["effects"]
    assert info["features"]["model_check"] is True
    assert info["limits"]["max_upload_bytes"] == UPLOAD_LIMIT
    assert info["limits"]["max_log_samples"] == LOG_ROWS_LIMIT
    spec = http.get("/openapi.json").json()
    for op in ("check", "diagnose", "fit"):
        body = spec["paths"][f"/v1/model-check/{op}"]["post"]["requestBody"]
        assert "multipart/form-data" in body["content"]


def test_check_json_and_html_report(http: httpx.Client, rig_csv: bytes) -> None:
    r = post(http, CHECK, ("rig.csv", rig_csv))
    assert r.status_code == 200, r.text[:500]
    d = r.json()
    assert d["kind"] == "time-series"
    # the missing friction shows: free-run speed error far above the speed sensor's noise
    assert d["free_run"]["rms"]["omega"] > 5 * d["noise"]["omega"]
    assert d["breakdown"]["direction"]["thrust >= 0"]["one_step_mean.mechanical"] < -0.5 * TAU_C
    page = http.post(CHECK, params={"report": "html"}, files={"log": ("rig.csv", rig_csv)},
                     data={"params": "paper-rig"})
    assert page.status_code == 200 and page.headers["content-type"].startswith("text/html")
    assert page.text.startswith("<!DOCTYPE html>") and page.text.count("data:image/png;base64,") == 4
    assert "rig.csv" in page.text and "called_input_delay" in page.text  # the alignment, in the summary
    # compared after the logging convention's lag (the rig logs on time), which is bounded before any work
    assert abs(d["alignment"]["samples"]) < 0.5 and not d["alignment"]["called_input_delay"]
    for path, form in ((CHECK, {}), ("/v1/model-check/fit", {"effects": "coulomb_friction"})):
        for bad in ("-1", "21"):
            got = problem(post(http, path, ("rig.csv", rig_csv), max_logging_skew=bad, **form), 422)
            assert got["field"] == "max_logging_skew", got


def test_parquet_recognised_by_content(http: httpx.Client, rig_csv: bytes, rig_log: Log) -> None:
    buf = io.BytesIO()
    pq.write_table(pa.table({k: v for k, v in rig_log.columns().items()}), buf)
    from_parquet = post(http, CHECK, ("upload.bin", buf.getvalue()))  # no telling suffix: the magic bytes decide
    assert from_parquet.status_code == 200, from_parquet.text[:500]
    from_csv = post(http, CHECK, ("rig.csv", rig_csv)).json()
    for stat in ("rms", "max"):
        assert from_parquet.json()["free_run"][stat] == pytest.approx(from_csv["free_run"][stat], rel=1e-9)


def test_diagnose_names_the_hidden_effect(http: httpx.Client, rig_csv: bytes) -> None:
    r = post(http, "/v1/model-check/diagnose", ("rig.csv", rig_csv))
    assert r.status_code == 200, r.text[:500]
    d = r.json()
    assert d["verdict"] == ["coulomb_friction"]
    top = d["ranking"][0]
    assert top["effect"] == "coulomb_friction" and top["significant"] is True
    assert top["parameters"]["tau_c"] == pytest.approx(TAU_C, rel=0.25)


def test_fit_answers_loadable_calibrated_params(http: httpx.Client, rig_csv: bytes) -> None:
    r = post(http, "/v1/model-check/fit", ("rig.csv", rig_csv), effects="coulomb_friction")
    assert r.status_code == 200, r.text[:500]
    d = r.json()
    assert d["effects"] == ["coulomb_friction"]
    assert d["rms_after"]["omega"] < 0.1 * d["rms_before"]["omega"]
    plant = load_plant(d["calibrated_params"])
    assert [e.name for e in plant.effects] == ["coulomb_friction"]
    assert plant.effects[0].tau_c == pytest.approx(TAU_C, rel=0.05)  # type: ignore[attr-defined]
    # the calibrated mapping goes back in as `params` (JSON text with an effects block): now at the noise
    again = post(http, CHECK, ("rig.csv", rig_csv), params=json.dumps(d["calibrated_params"])).json()
    assert again["free_run"]["rms"]["omega"] < 1.3 * RigSpec().noise_omega


def test_log_problems_name_the_column_or_the_log(http: httpx.Client, rig_csv: bytes) -> None:
    header, rest = rig_csv.split(b"\n", 1)
    # no speed at all (issue #13: only the speed is needed by every equation; a missing thrust only disables
    # the thrust equation, below)
    renamed = header.replace(b"omega", b"speed").replace(b"theta", b"angle") + b"\n" + rest
    p = problem(post(http, CHECK, ("rig.csv", renamed)), 422)
    assert p["field"] == "omega" and "missing column" in str(p["reason"])
    assert p["form_field"] == "log"  # where a page shows it
    # ... and the column map fixes it
    ok = post(http, CHECK, ("rig.csv", renamed), columns=json.dumps({"omega": {"column": "speed", "unit": "rad/s"}}))
    assert ok.status_code == 200, ok.text[:500]
    p = problem(post(http, CHECK, ("rig.csv", renamed), columns='{"omega": {"column": "speed", "unit": "furlong"}}'),
                422)
    assert p["field"] == "columns" and "furlong" in str(p["reason"])
    no_thrust = post(http, CHECK, ("rig.csv", header.replace(b"thrust", b"force") + b"\n" + rest)).json()
    assert {e["equation"]: e["checked"] for e in no_thrust["equations"]} == {
        "thrust": False, "mechanical": True, "electrical": True, "power": False}
    p = problem(post(http, CHECK, ("rig.csv", rig_csv), columns="[1, 2"), 422)
    assert p["field"] == p["form_field"] == "columns"
    p = problem(post(http, CHECK, None), 422)
    assert p["field"] == "log"
    p = problem(post(http, CHECK, ("rig.csv", b"\xff\xfe\x00 not a log")), 422)
    assert p["field"] == "log" and "CSV" in str(p["reason"])
    p = problem(post(http, CHECK, ("rig.parquet", rig_csv)), 422)
    assert p["field"] == "log" and "Parquet" in str(p["reason"]) and "/tmp" not in str(p["reason"])


def test_params_problems(http: httpx.Client, rig_csv: bytes) -> None:
    p = problem(post(http, CHECK, ("rig.csv", rig_csv), params='{"J": 2.7e-5,'), 422)
    assert p["field"] == "params" and "JSON" in str(p["reason"])
    p = problem(post(http, CHECK, ("rig.csv", rig_csv), params="/etc/hostname"), 422)
    assert p["field"] == "params" and "files are not read" in str(p["reason"])
    p = problem(post(http, CHECK, ("rig.csv", rig_csv), params='{"effects": {"warp_drive": {}}}'), 422)
    assert p["field"] == "params"
    p = problem(post(http, CHECK, ("rig.csv", rig_csv), params="[1, 2]"), 422)
    assert p["field"] == "params"


def test_fit_effects_problems(http: httpx.Client, rig_csv: bytes) -> None:
    p = problem(post(http, "/v1/model-check/fit", ("rig.csv", rig_csv), effects="coulomb_friction,warp_drive"), 422)
    assert p["field"] == p["form_field"] == "effects" and "warp_drive" in str(p["reason"])
    p = problem(post(http, "/v1/model-check/fit", ("rig.csv", rig_csv), effects=" , "), 422)
    assert p["field"] == "effects"
    p = problem(post(http, "/v1/model-check/fit", ("rig.csv", rig_csv)), 422)
    assert p["field"] == "effects" and p["reason"] == "missing field"


def test_size_limits(http: httpx.Client) -> None:
    # just over the upload limit: the route refuses it, naming the log
    p = problem(post(http, CHECK, ("big.csv", b"#" * (UPLOAD_LIMIT + 1))), 413)
    assert p["field"] == "log"
    # far over it: the body limit refuses it before it is read, still naming the log
    p = problem(post(http, CHECK, ("huge.csv", b"#" * (3 * UPLOAD_LIMIT))), 413)
    assert p["field"] == "log"
    # within the byte limit but too many rows
    rows = "\n".join(f"{k * 1e-3:.3f},1,0,1,0" for k in range(LOG_ROWS_LIMIT + 1))
    p = problem(post(http, CHECK, ("long.csv", f"t,voltage,current,omega,thrust\n{rows}\n".encode())), 422)
    assert p["field"] == "log" and str(LOG_ROWS_LIMIT) in str(p["reason"])
    assert http.get("/healthz").json()["status"] == "ok"


def _children(pid: int) -> list[int]:
    return [int(c) for task in Path(f"/proc/{pid}/task").iterdir()
            for c in (task / "children").read_text().split()]


def _peak_rss_mb(pid: int) -> float:
    """Peak resident memory [MB] of a process so far (VmHWM from /proc)."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("VmHWM:"):
            return int(line.split()[1]) / 1024.0
    raise AssertionError("no VmHWM")


def test_parquet_bomb_is_refused_from_its_footer(http: httpx.Client, server: Server) -> None:
    """Issue #12, finding 4: 69 KB of Parquet announcing 3 M rows (120 MB decoded) is refused from its metadata,
    before decoding: the reason quotes the announced row count and no worker's peak memory grows by 50 MB."""
    zeros = np.zeros(3_000_000)
    buf = io.BytesIO()
    pq.write_table(pa.table({c: zeros for c in ("t", "voltage", "current", "omega", "thrust")}), buf,
                   compression="zstd")
    assert len(buf.getvalue()) < UPLOAD_LIMIT
    workers = _children(server.proc.pid)
    before = {w: _peak_rss_mb(w) for w in workers}
    p = problem(post(http, CHECK, ("bomb.parquet", buf.getvalue())), 422)
    assert p["field"] == "log" and "announces 3000000 rows" in p["reason"], p
    assert all(_peak_rss_mb(w) - before[w] < 50.0 for w in workers if Path(f"/proc/{w}").exists())


def _xlsx_bomb() -> bytes:
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=9) as z:
        z.writestr("xl/worksheets/sheet1.xml", b" " * 150_000_000)
    return buf.getvalue()


def _mat_bomb() -> bytes:
    buf = io.BytesIO()
    sio.savemat(buf, {"t": np.zeros(3_000_000), "rpm": np.zeros(3_000_000)}, do_compression=True)
    return buf.getvalue()


@pytest.mark.parametrize(("name", "make"), [("bomb.xlsx", _xlsx_bomb), ("bomb.mat", _mat_bomb)])
def test_xlsx_and_mat_bombs_are_refused_before_decoding(http: httpx.Client, server: Server, name: str,
                                                        make: Callable[[], bytes]) -> None:
    """A workbook whose sheet inflates to 150 MB and a .mat file of 48 MB of zeros, each under the upload limit,
    are refused from their headers (the zip's directory; the .mat elements inflated in chunks and counted)
    against the server's row limit: 422 on ``log``, and no worker's peak memory grows by 50 MB."""
    data = make()
    assert len(data) < UPLOAD_LIMIT
    workers = _children(server.proc.pid)
    before = {w: _peak_rss_mb(w) for w in workers}
    p = problem(post(http, CHECK, (name, data)), 422)
    assert p["field"] == "log" and "expands to more than" in p["reason"], p
    assert all(_peak_rss_mb(w) - before[w] < 50.0 for w in workers if Path(f"/proc/{w}").exists())
