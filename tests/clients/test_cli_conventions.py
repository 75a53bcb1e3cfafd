"""The command line behaves like a well-kept Unix tool: ``--version``, a light start-up (no numerical
stack imported for ``--help``), ``-`` as stdin/stdout, a quiet exit on a closed pipe, JSON errors
under ``--json``, help with a description, an example and the accepted names; and the examples a
newcomer runs (``examples/params.yaml``, ``examples/missions/``, the README tour) run as they are."""

from __future__ import annotations

import csv
import io
import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from ocp.model.params import load_params

ROOT = Path(__file__).resolve().parents[2]
CLI = [sys.executable, "-m", "clients.cli"]
HEAVY = ("numpy", "scipy", "matplotlib", "casadi", "pydantic", "httpx", "ocp.model.params", "ocp.optimize.mission")


def cli(*argv: str, stdin: str | None = None, check: bool = True) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*CLI, *argv], cwd=ROOT, input=stdin, capture_output=True, text=True, check=check,
                          timeout=300)


def test_version_and_help_import_nothing_heavy() -> None:
    code = ("import sys, contextlib, io\n"
            "from clients.cli import build_parser\n"
            "with contextlib.redirect_stdout(io.StringIO()):\n"
            "    try:\n"
            "        build_parser().parse_args(['--help'])\n"
            "    except SystemExit:\n"
            "        pass\n"
            f"print([m for m in {HEAVY!r} if m in sys.modules])")
    run = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True)
    assert json.loads(run.stdout.replace("'", '"')) == [], "imported at start-up: " + run.stdout
    version = cli("--version").stdout.split()
    assert version[0] == "thrustshape" and version[1][0].isdigit()


def help_text(command: str, capsys: pytest.CaptureFixture[str]) -> str:
    from clients.cli import main

    with pytest.raises(SystemExit) as exit_:
        main([command, "--help"])
    assert exit_.value.code == 0
    return capsys.readouterr().out


def test_subcommand_help_has_description_example_and_names(capsys: pytest.CaptureFixture[str]) -> None:
    text = help_text("fit", capsys)
    assert "examples:" in text and "thrustshape fit rig.csv" in text
    assert "paper-rig" in text and "coulomb_friction" in text and "brush_drop" in text  # presets and effects
    text = help_text("optimize", capsys)
    assert "continuous-voltage" in text and "'-': stdin" in text and "--plot" in text


def test_optimize_reads_stdin_writes_csv_to_stdout_and_plots(tmp_path: Path) -> None:
    mission = json.loads((ROOT / "examples/reversal.json").read_text())
    mission["collocation"] = {"intervals": 60}
    plot = tmp_path / "ref.svg"
    run = cli("optimize", "-", "--out", "-", "--plot", str(plot), stdin=json.dumps(mission))
    rows = list(csv.DictReader(io.StringIO(run.stdout)))
    assert list(rows[0]) == ["t", "thrust", "thrust_desired", "omega", "theta", "current", "voltage"]
    t = np.array([float(r["t"]) for r in rows])
    f, fd = (np.array([float(r[k]) for r in rows]) for k in ("thrust", "thrust_desired"))
    assert len(rows) > 1000 and np.all(np.diff(t) > 0)
    assert math.sqrt(float(np.mean((f - fd) ** 2))) < 0.02  # the optimised thrust tracks the desired one
    assert max(abs(float(r["current"])) for r in rows) <= 1.0 * (1 + 1e-6)  # within the mission's limit
    assert "mission reversal-2s" in run.stderr  # the summary moved to stderr
    svg = plot.read_text()
    assert svg.startswith("<?xml") and "<svg" in svg and len(svg) > 20_000


def test_a_closed_pipe_ends_quietly(tmp_path: Path) -> None:
    src = tmp_path / "volts.csv"  # 4 s at 1 kHz: the answer is far more than a pipe buffer
    t = np.linspace(0.0, 4.0, 4001)
    src.write_text("t,voltage\n" + "".join(f"{a:.6f},{b:.9f}\n" for a, b in zip(t, 6 * np.sin(3 * t), strict=True)))
    proc = subprocess.Popen([*CLI, "simulate", str(src), "--params", "paper-rig"], cwd=ROOT,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    assert proc.stdout is not None and proc.stderr is not None
    assert proc.stdout.readline().startswith(b"t,voltage,omega")
    proc.stdout.close()  # `| head -1`
    with proc.stderr:
        err = proc.stderr.read().decode()
    assert proc.wait(120) in (0, 141) and err == "", err


def test_errors_are_json_under_json_flag(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                         monkeypatch: pytest.MonkeyPatch) -> None:
    from clients.cli import main

    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"segments": [{"kind": "hold", "duration": 1, "thrust": 0.1}],
                               "limits": {"voltage": -3}}))
    assert main(["optimize", str(bad), "--json"]) == 1
    out = capsys.readouterr()
    problem = json.loads(out.err)
    assert out.out == "" and problem["field"] == "limits.voltage" and problem["error_type"] == "MissionError"
    with pytest.raises(SystemExit) as exit_:  # a usage error
        main(["optimize", "--json"])
    assert exit_.value.code == 2 and json.loads(capsys.readouterr().err)["error_type"] == "UsageError"
    assert main(["optimize", str(tmp_path / "nowhere.json"), "--plot", "x.gif", "--json"]) == 1
    assert json.loads(capsys.readouterr().err)["field"] == "--plot"  # refused before any work
    monkeypatch.setattr("sys.stdin", io.StringIO(bad.read_text()))  # `-` is stdin; no --json: one plain line
    assert main(["optimize", "-"]) == 1
    assert capsys.readouterr().err.startswith("thrustshape optimize: error: limits.voltage")


def test_example_parameter_file_converts_its_units() -> None:
    """examples/params.yaml is the paper-rig preset written per rpm^2: loading it gives the preset back."""
    mine, preset = load_params(ROOT / "examples/params.yaml"), load_params("paper-rig")
    for key in ("J", "B", "k_t", "k_e", "R", "L"):
        assert getattr(mine, key) == getattr(preset, key)
    rpm = 2 * math.pi / 60  # rad/s per rpm: c [N/rpm^2] = c [N/(rad/s)^2] * rpm^2
    for key in ("c_f", "c_tau"):
        assert getattr(mine, key) == pytest.approx(getattr(preset, key), rel=5e-5)
        assert getattr(mine, key) != pytest.approx(getattr(preset, key) * rpm**2, rel=0.5)


def test_example_missions_and_readme_tour_run_as_they_are(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                                          monkeypatch: pytest.MonkeyPatch) -> None:
    from clients.cli import main
    from clients.cli.service import load_missions

    missions = load_missions(ROOT / "examples/missions")
    assert len(missions) >= 4 and len({m.name for m in missions}) == len(missions)
    tour = [line.strip() for line in (ROOT / "README.md").read_text().split("## A short tour")[1]
            .split("```bash")[1].split("```")[0].splitlines() if line.startswith("thrustshape ")]
    assert any(" simulate " in line for line in tour)
    monkeypatch.chdir(tmp_path)  # a fresh directory: the tour must make the files it reads
    for line in tour:
        if any(f" {cmd} " in line for cmd in ("batch", "optimize")) or line.endswith("--version"):
            continue  # solves (covered above and by the batch tests); --version exits through argparse
        argv, _, out = line.split("#")[0].partition(">")
        assert main(argv.split()[1:]) == 0, f"{line}: {capsys.readouterr().err}"
        text = capsys.readouterr().out
        if out.strip():
            (tmp_path / out.strip()).write_text(text)
    response = list(csv.DictReader(io.StringIO((tmp_path / "response.csv").read_text())))
    assert len(response) > 1000 and max(abs(float(r["thrust"])) for r in response) > 0.3


def test_logs_and_batches_read_from_stdin(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                          monkeypatch: pytest.MonkeyPatch) -> None:
    from clients.cli import main
    from clients.cli.service import load_missions
    from ocp.logs import write_log_csv
    from tests.synthetic_rig import RigSpec, generate

    log = tmp_path / "rig.csv"
    write_log_csv(generate(load_params("paper-rig"), RigSpec(seconds=0.4, seed=5)), log)
    assert main(["check", str(log), "--params", "paper-rig", "--json"]) == 0
    from_file = json.loads(capsys.readouterr().out)
    monkeypatch.setattr("sys.stdin", io.TextIOWrapper(io.BytesIO(log.read_bytes())))
    assert main(["check", "-", "--params", "paper-rig", "--json"]) == 0
    assert json.loads(capsys.readouterr().out) == from_file  # `check - < rig.csv` is `check rig.csv`
    example = json.loads((ROOT / "examples/reversal.json").read_text())
    docs = "missions:\n" + "".join(f"  - {json.dumps({**example, 'name': n})}\n" for n in ("a", "b"))  # YAML
    monkeypatch.setattr("sys.stdin", io.StringIO(docs))
    assert [m.name for m in load_missions("-")] == ["a", "b"]
