"""``--server URL`` of ``optimize``, ``compare``, ``check``, ``diagnose`` and ``fit``, against one real
uvicorn server (module-scoped, API key required): each prints what the local path prints, and the
server's errors reach the user naming the field."""

from __future__ import annotations

import asyncio
import json
import math
import sqlite3
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from clients import AsyncClient, InvalidInput
from clients.cli import main
from ocp.logs import negated, read_log, write_log_csv
from ocp.model.effects import load_plant
from ocp.model.params import MotorParams
from tests.service.test_service_support import Server, start_server
from tests.synthetic_rig import RigSpec, generate

pytestmark = pytest.mark.integration

KEY = "cli-test-key"


@pytest.fixture(scope="module")
def server(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Server]:
    tmp = tmp_path_factory.mktemp("cli-server")
    srv = start_server(tmp, {"TS_TEST_TASKS": "real", "THRUSTSHAPE_DB_PATH": str(tmp / "jobs.db"),
                             "THRUSTSHAPE_API_KEY": KEY, "OPENBLAS_NUM_THREADS": "1"})
    yield srv
    srv.stop()


@pytest.fixture(scope="module")
def rig_csv(rig: MotorParams, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """3 s at 1 kHz from a rig with a brush drop the nominal model lacks."""
    path = tmp_path_factory.mktemp("log") / "rig.csv"
    write_log_csv(generate(rig, RigSpec(effects={"brush_drop": {"v_b": 0.3}}, seconds=1.0, seed=3)), path)
    return path


@pytest.fixture(scope="module")
def mission_file(rig: MotorParams, tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A small reversal whose parameters live in a local file (the client reads it; the server reads none)."""
    tmp = tmp_path_factory.mktemp("mission")
    (tmp / "motor.json").write_text(json.dumps(rig.model_dump()), encoding="utf-8")
    mission = {"name": "flip", "params": str(tmp / "motor.json"), "collocation": {"intervals": 40},
               "segments": [{"kind": "hold", "duration": 0.2, "thrust": 0.3},
                            {"kind": "reversal", "duration": 0.8, "to": -0.3},
                            {"kind": "hold", "duration": 0.2, "thrust": -0.3}]}
    path = tmp / "flip.json"
    path.write_text(json.dumps(mission), encoding="utf-8")
    return path


def run(argv: list[str], capsys: pytest.CaptureFixture[str]) -> tuple[int, str, str]:
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def both(argv: list[str], server: Server, capsys: pytest.CaptureFixture[str]) -> tuple[str, str]:
    """stdout of the local run and of the ``--server`` run of the same command (each must succeed)."""
    code, local, err = run(argv, capsys)
    assert code == 0, err
    code, remote, err = run([*argv, "--server", server.url, "--api-key", KEY], capsys)
    assert code == 0, err
    return local, remote


def jobs_run(server: Server, op: str) -> int:
    """How many ``op`` model-check jobs the server has stored (its SQLite file, beside its log)."""
    with sqlite3.connect(server.log.parent / "jobs.db") as db:
        return int(db.execute("SELECT COUNT(*) FROM model_checks WHERE op = ?", (op,)).fetchone()[0])


def close(a: Any, b: Any, rel: float = 1e-9, path: str = "") -> None:
    """Recursive equality, floats to ``rel`` (two processes may round the last bits differently)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and set(a) == set(b), f"{path}: keys {set(a) ^ set(b)}"
        for k in a:
            close(a[k], b[k], rel, f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), path
        for i, (x, y) in enumerate(zip(a, b, strict=True)):
            close(x, y, rel, f"{path}[{i}]")
    elif isinstance(a, float) and not isinstance(b, bool):
        assert isinstance(b, int | float) and math.isclose(a, b, rel_tol=rel, abs_tol=1e-12), f"{path}: {a} != {b}"
    else:
        assert a == b, f"{path}: {a!r} != {b!r}"


def test_check_json_text_and_report(server: Server, rig_csv: Path, tmp_path: Path,
                                    capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["check", str(rig_csv), "--params", "paper-rig"]
    before = jobs_run(server, "check")
    local, remote = both([*argv, "--json"], server, capsys)
    assert jobs_run(server, "check") == before + 1  # a job: no request timeout on a long log
    close(json.loads(local), json.loads(remote))
    local, remote = both(argv, server, capsys)
    assert remote == local and remote.startswith("alignment: command acts") and "\nfree run (model simulated" in remote
    report = tmp_path / "report.html"
    code, _, err = run([*argv, "--report", str(report), "--server", server.url, "--api-key", KEY], capsys)
    assert code == 0, err
    assert report.read_text(encoding="utf-8").count("data:image/png;base64,") == 4


def test_diagnose_names_the_effect_like_the_local_run(server: Server, rig_csv: Path,
                                                      capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["diagnose", str(rig_csv), "--params", "paper-rig", "--max-effects", "1"]
    local, remote = both([*argv, "--json"], server, capsys)
    assert json.loads(remote)["verdict"] == ["brush_drop"]
    close(json.loads(local), json.loads(remote))
    local, remote = both(argv, server, capsys)
    assert remote == local and remote.startswith("missing: brush_drop")


def test_fit_writes_the_same_calibrated_file(server: Server, rig_csv: Path, tmp_path: Path,
                                             capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["fit", str(rig_csv), "--params", "paper-rig", "--effects", "brush_drop"]
    before = jobs_run(server, "fit")
    code, local, err = run([*argv, "--out", str(tmp_path / "local.json")], capsys)
    assert code == 0, err
    code, remote, err = run([*argv, "--out", str(tmp_path / "remote.json"), "--server", server.url,
                             "--api-key", KEY], capsys)
    assert code == 0, err
    assert remote == local and "brush_drop.v_b" in remote
    assert jobs_run(server, "fit") == before + 1
    close(json.loads((tmp_path / "local.json").read_text()), json.loads((tmp_path / "remote.json").read_text()))
    plant = load_plant(tmp_path / "remote.json")
    assert plant.effects[0].v_b == pytest.approx(0.3, rel=0.05)  # type: ignore[attr-defined]


def test_optimize_sends_the_local_parameter_file(server: Server, mission_file: Path, tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    local, remote = both(["optimize", str(mission_file), "--json"], server, capsys)
    a, b = json.loads(local), json.loads(remote)
    assert b["source"] == "optimized"
    for k in ("solve_time_s", "total_time_s", "solver"):  # timings differ between runs
        a.pop(k), b.pop(k)
    close(a, b, rel=1e-6)
    code, text, err = run(["optimize", str(mission_file), "--out", str(tmp_path / "ref.csv"), "--server", server.url,
                           "--api-key", KEY], capsys)
    assert code == 0, err
    assert text.startswith("mission flip: optimized") and "reversal at" in text
    lines = (tmp_path / "ref.csv").read_text().splitlines()
    assert lines[0] == "t,thrust,thrust_desired,omega,theta,current,voltage" and len(lines) == len(a["t"]) + 1


def test_compare_table_and_plot_match(server: Server, mission_file: Path, tmp_path: Path,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    local, remote = both(["compare", str(mission_file), "--qs", "0,2"], server, capsys)
    assert remote == local
    assert [ln.split()[0] for ln in remote.splitlines()[1:]] == ["optimized", "sin^1", "sin^5"]
    # the server's answer carries the curves, so the plot is drawn from it as from a local run
    code, _, err = run(["compare", str(mission_file), "--qs", "0,2", "--plot", str(tmp_path / "p.png"),
                        "--server", server.url, "--api-key", KEY], capsys)
    assert code == 0, err
    assert (tmp_path / "p.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert (tmp_path / "p.png").stat().st_size > 10_000


def test_server_errors_name_the_field(server: Server, rig_csv: Path, monkeypatch: pytest.MonkeyPatch,
                                      capsys: pytest.CaptureFixture[str]) -> None:
    argv = ["fit", str(rig_csv), "--params", "paper-rig", "--effects", "warp_drive", "--server", server.url]
    code, _, err = run([*argv, "--api-key", KEY], capsys)
    assert code == 1 and "422" in err and "effects" in err and "warp_drive" in err
    code, _, err = run([*argv, "--api-key", "wrong"], capsys)
    assert code == 1 and "401" in err
    monkeypatch.setenv("THRUSTSHAPE_API_KEY", KEY)  # the key from the environment
    code, _, err = run(["check", str(rig_csv), "--params", "paper-rig", "--columns", '{"thrust": "force"}',
                        "--server", server.url], capsys)
    assert code == 1 and "422" in err and "force: missing column" in err


def test_a_negated_current_is_refused_and_read_back_with_negate(server: Server, rig_csv: Path, tmp_path: Path,
                                                                 capsys: pytest.CaptureFixture[str]) -> None:
    """The project's own rig log with its current negated: the worker refuses it naming the field (the sign
    check, :mod:`ocp.identify.signs`); the form field ``negate`` reads it back, and the verdict is the unflipped
    log's (the local run's, as the other tests here)."""
    log = read_log(rig_csv)
    flipped = tmp_path / "flipped.csv"
    write_log_csv(negated(log, ["current"]), flipped)
    argv = ["diagnose", str(flipped), "--params", "paper-rig", "--max-effects", "1", "--server", server.url,
            "--api-key", KEY]
    code, _, err = run(argv, capsys)
    assert code == 1 and "current" in err and "opposite sign" in err and "--negate current" in err
    code, out, err = run([*argv, "--negate", "current", "--json"], capsys)
    assert code == 0, err
    d = json.loads(out)
    assert d["verdict"] == ["brush_drop"] and "negated as asked: current" in d["notes"]


def test_async_client_model_check(server: Server, rig_csv: Path, rig: MotorParams) -> None:
    async def scenario() -> None:
        async with AsyncClient(server.url, api_key=KEY) as c:
            checked = await c.check(rig_csv, "paper-rig")
            assert checked["free_run"]["rms"]["omega"] > 5 * checked["noise"]["omega"]
            page = await c.check_report(("rig.csv", rig_csv.read_bytes()), "paper-rig")
            assert page.startswith("<!DOCTYPE html>")
            found = await c.diagnose(rig_csv, rig.model_dump(), max_effects=1, corrections=False)
            assert found["verdict"] == ["brush_drop"]
            fitted = await c.fit(rig_csv, rig.model_dump(), found["verdict"], refine=False)
            assert fitted["stage"] == "equation-error"
            assert fitted["calibrated_params"]["effects"]["brush_drop"]["v_b"] == pytest.approx(0.3, rel=0.05)
            with pytest.raises(InvalidInput) as bad:
                await c.fit(rig_csv, "paper-rig", "warp_drive")
            assert bad.value.field == "effects"

    asyncio.run(scenario())
