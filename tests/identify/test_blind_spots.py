"""What a log cannot show, said beside the diagnosis (issue #11: "an effect cannot show in the log"): a rig with a
hidden voltage dead band logged under random steps between +-0.6 V_max (one voltage magnitude, where the dead band
is a gain on the command) is diagnosed without it; the diagnosis says the log holds one voltage magnitude and that
a dead band or a brush drop cannot show there, in the JSON and the CLI text. Under four voltage levels the gap is
gone and the dead band is named."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from clients.cli import main
from ocp.identify import diagnose
from ocp.identify.coverage import GAPS, blind_spots, coverage
from ocp.logs import log_from_arrays, write_log_csv
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground.experiment import draw, run_command, voltage_steps
from tests.rig_log import rig_log

SEED = 0  # a 200 Hz rig whose two-level log misses its dead band (test_design_experiment's); any such rig holds


def _log(rig, levels: tuple[float, ...]):  # type: ignore[no-untyped-def]
    t, v = voltage_steps(rig, SEED, levels=levels)
    return rig_log(run_command(rig, t, v, SEED + 1))


def test_a_two_level_log_says_it_cannot_show_a_dead_band(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = draw(SEED, "voltage_deadband")
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    two = _log(rig, (-1.0, 1.0))
    res = diagnose(plant, two)
    assert "voltage_deadband" not in res.verdict
    spots = {b["gap"]: b for b in res.to_dict()["blind_spots"]}
    assert spots["voltage_range"]["hidden"] == [h for h in GAPS["voltage_range"] if h not in res.verdict]
    assert "one voltage magnitude" in spots["voltage_range"]["text"]
    # every gap coverage() finds is reported, and only those
    cov = coverage(two)
    assert set(spots) <= {g for g in GAPS if not cov[g]}

    csv, params = tmp_path / "two-level.csv", tmp_path / "nominal.json"
    write_log_csv(two, csv)
    params.write_text(json.dumps(rig.nominal))
    assert main(["diagnose", str(csv), "--params", str(params)]) == 0
    assert "this log cannot show voltage_deadband" in capsys.readouterr().out

    four = _log(rig, (-1.0, -0.3, 0.3, 1.0))
    again = diagnose(plant, four)
    assert coverage(four)["voltage_range"] and "voltage_range" not in {b["gap"] for b in again.blind_spots}
    assert again.verdict == ["voltage_deadband"]


def test_what_the_verdict_names_is_not_a_blind_spot() -> None:
    t = np.arange(400) * 1e-3
    v = np.where(np.sin(2 * np.pi * 3 * t) > 0, 6.0, -6.0)  # +-6 V: one magnitude, reversing
    log = log_from_arrays(t, v, 0.1 * v, 0 * v, omega=10 * v)
    assert [b["hidden"] for b in blind_spots(log) if b["gap"] == "voltage_range"] == [["voltage_deadband",
                                                                                       "brush_drop"]]
    assert [b["hidden"] for b in blind_spots(log, ["brush_drop"]) if b["gap"] == "voltage_range"] == [
        ["voltage_deadband"]]
    assert "voltage_range" not in {b["gap"] for b in blind_spots(log, ["brush_drop", "voltage_deadband"])}
