"""``thrustshape batch --local`` on the service's worker pool: a mission's local parameter file is still read
(here, once, and sent to the workers as its mapping: the workers refuse file paths), with real solves."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from clients.cli import main
from service.tasks import available_tasks
from tests.service.test_service_support import ROOT, mission


@pytest.mark.slow
@pytest.mark.skipif(available_tasks().optimize is None, reason="ocp.optimize.solve is not installed")
def test_local_batch_reads_a_parameter_file_here_and_matches_the_preset(tmp_path: Path,
                                                                        capsys: pytest.CaptureFixture[str]) -> None:
    # examples/params.yaml is the paper-rig preset in datasheet units, its coefficients rounded to 5 digits
    # (c_f, c_tau within 3e-5 relative): the same motor, so the same answer within 1e-3
    src = tmp_path / "missions.json"
    src.write_text(json.dumps({"missions": [
        mission("file", collocation={"intervals": 40}, params=str(ROOT / "examples" / "params.yaml")),
        mission("preset", collocation={"intervals": 40}, params="paper-rig")]}))
    assert main(["batch", str(src), "--local", "--workers", "1", "--json", "--out", str(tmp_path / "out")]) == 0
    rows = json.loads(capsys.readouterr().out)["summary"]
    assert [r["status"] for r in rows] == ["done", "done"] and rows[0]["source"] == "optimized"
    assert rows[0]["max_abs_current"] == pytest.approx(rows[1]["max_abs_current"], rel=1e-3)
    assert rows[0]["thrust_rms_error"] == pytest.approx(rows[1]["thrust_rms_error"], rel=1e-3, abs=1e-9)
    for row in rows:  # the per-mission files are strict JSON of the same answers
        item = json.loads((tmp_path / "out" / f"{row['index']:04d}-{row['name']}.json").read_text(encoding="utf-8"),
                          parse_constant=lambda c: pytest.fail(f"non-standard JSON constant {c}"))
        assert item["name"] == row["name"] and item["status"] == "done"
        assert item["result"]["verification"]["max_abs_current"] == row["max_abs_current"]
        assert len(item["result"]["t"]) == len(item["result"]["thrust"]) > 100
