"""The new formats and read options through the CLI (in process) and the API (a real uvicorn server, one
worker): a vendor .xlsx sweep, a PX4 ULog, pole pairs and the ESC neutral as form fields, bad options named."""

from __future__ import annotations

import json
from collections.abc import Iterator
from pathlib import Path

import httpx
import numpy as np
import pytest

from clients.cli import main
from tests.logfiles import RPM, Thruster, thruster_sweep, tyto_series, write_csv, write_ulog, write_xlsx
from tests.service.test_service_support import Server, problem, start_server

DIAGNOSE = "/v1/model-check/diagnose"


def test_cli_diagnoses_a_vendor_sweep_and_lists_the_equations(tmp_path: Path,
                                                              capsys: pytest.CaptureFixture[str]) -> None:
    th = Thruster(ratio=0.8)
    write_csv(thruster_sweep(th), tmp_path / "sweep.csv", title="Thruster at 16 V")
    (tmp_path / "thruster.json").write_text(json.dumps(th.params()))
    assert main(["diagnose", str(tmp_path / "sweep.csv"), "--params", str(tmp_path / "thruster.json")]) == 0
    out = capsys.readouterr().out
    assert "missing: thrust_asymmetry" in out and "not checked electrical" in out and "checked     power" in out
    assert main(["diagnose", str(tmp_path / "sweep.csv"), "--params", str(tmp_path / "thruster.json"),
                 "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert abs(d["fitted_maps"]["thrust_ratio_reverse_to_forward"] - 0.8) < 0.02


def test_cli_pole_pairs_and_bad_range(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    cols, _ = tyto_series("us-kg")
    write_csv(cols, tmp_path / "tyto.csv")
    args = ["check", str(tmp_path / "tyto.csv"), "--params", "paper-rig", "--json"]
    assert main(args) == 1 and "pole pairs" in capsys.readouterr().err
    assert main([*args, "--pole-pairs", "7"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert any("divided by 7 pole pairs" in n for n in d["notes"])
    assert main([*args, "--pole-pairs", "7", "--throttle-range", "1900,x"]) == 1
    assert "--throttle-range" in capsys.readouterr().err


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("readers-api")
    srv = start_server(tmp, {"THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"), "OPENBLAS_NUM_THREADS": "1"})
    yield srv
    srv.stop()


@pytest.mark.integration
def test_api_reads_an_xlsx_sweep_and_a_ulog(http: httpx.Client, tmp_path: Path) -> None:
    pytest.importorskip("openpyxl")
    pytest.importorskip("pyulog")
    th = Thruster(ratio=0.8)
    write_xlsx(thruster_sweep(th), tmp_path / "sweep.xlsx")
    params = json.dumps(th.params())
    r = http.post(DIAGNOSE, files={"log": ("vendor.xlsx", (tmp_path / "sweep.xlsx").read_bytes())},
                  data={"params": params})
    assert r.status_code == 200, r.text
    d = r.json()
    assert d["route"] == "point-by-point" and "thrust_asymmetry" in d["verdict"]
    assert abs(d["fitted_maps"]["thrust_ratio_reverse_to_forward"] - 0.8) < 0.02
    assert {e["equation"]: e["checked"] for e in d["equations"]}["electrical"] is False
    t = 1.0 + np.arange(300) * 0.02
    u = 0.8 * np.sin(2 * np.pi * (t - 1.0) / 4.0)
    w = th.speed(1500 + 400 * u)
    write_ulog(tmp_path / "f.ulg", t * 1e6, np.abs(w) / RPM, 16 + 0 * t, th.supply_power(w) / 16, t * 1e6, u,
               motor=1)
    r = http.post("/v1/model-check/check", files={"log": ("flight", (tmp_path / "f.ulg").read_bytes())},
                  data={"params": params, "motor": "1"})
    assert r.status_code == 200, r.text
    eq = {e["equation"]: e for e in r.json()["equations"]}
    assert not eq["thrust"]["checked"] and eq["power"]["checked"]


@pytest.mark.integration
def test_api_names_bad_read_options(http: httpx.Client, tmp_path: Path) -> None:
    write_csv(thruster_sweep(), tmp_path / "s.csv")
    data = (tmp_path / "s.csv").read_bytes()
    r = http.post(DIAGNOSE, files={"log": ("s.csv", data)}, data={"params": "paper-rig", "throttle_range_us": "a,b"})
    assert problem(r, 422)["field"] == "throttle_range_us"
    r = http.post(DIAGNOSE, files={"log": ("s.csv", data)}, data={"params": "paper-rig", "pole_pairs": "0"})
    assert r.status_code == 422 and "pole_pairs" in r.text
    r = http.post(DIAGNOSE, files={"log": ("s.csv", data)}, data={"params": "paper-rig", "neutral_us": "1500",
                                                                 "throttle_range_us": "1600,1900"})
    assert problem(r, 422)["field"] == "throttle_range_us"
