"""What a log cannot show, said beside the diagnosis (issue #11: "an effect cannot show in the log"): a rig with a
hidden voltage dead band logged under random steps between +-0.6 V_max (one voltage magnitude, where the dead band
is a gain on the command) is diagnosed without it; the diagnosis says the log holds one voltage magnitude and that
a dead band or a brush drop cannot show there, in the JSON and the CLI text. Under four voltage levels the gap is
gone and the dead band is named. A sweep that turns one way only cannot show a drag or thrust asymmetry."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from clients.cli import main
from ocp.identify import diagnose
from ocp.identify.coverage import GAIN, GAPS, blind_spots, coverage
from ocp.logs import Log, log_from_arrays, read_log, write_log_csv
from ocp.model.effects import load_plant
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.logfiles import write_csv
from tests.proving_ground.experiment import Rig, draw, run_command, voltage_steps
from tests.rig_log import rig_log

SEED = 0  # a 200 Hz rig whose two-level log misses its dead band (test_design_experiment's); any such rig holds


def _log(rig: Rig, levels: tuple[float, ...]) -> Log:
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
    named = [v for v in res.verdict if v in GAIN]  # R (and k, J) taking up the dead band's gain
    text = spots["voltage_range"]["text"]
    assert named and f"corrections named here ({', '.join(named)}) fit as one gain on it" in text
    # every gap coverage() finds is reported, and only those
    cov = coverage(two)
    assert set(spots) <= {g for g in GAPS if not cov[g]}

    csv, params = tmp_path / "two-level.csv", tmp_path / "nominal.json"
    write_log_csv(two, csv)
    params.write_text(json.dumps(rig.nominal))
    assert main(["diagnose", str(csv), "--params", str(params)]) == 0
    out = capsys.readouterr().out
    assert "this log cannot show voltage_deadband" in out and "(design-experiment proposes a run that can)" in out

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


def _sweep(w: np.ndarray, path: Path) -> Log:
    """A noise-free sweep of the plant ``P`` at the speeds ``w`` [rad/s] (its steady current, voltage and thrust in
    closed form: eqs. dc_mechanical and dc_electrical with zero derivatives), read as a steady-state log."""
    i = (P["B"] * w + P["c_tau"] * w * np.abs(w)) / P["k_t"]
    write_csv({"voltage": P["R"] * i + P["k_e"] * w, "current": i, "omega": w, "thrust": P["c_f"] * w * np.abs(w)},
              path)
    return read_log(path, kind="steady-state")


P = {"J": 2e-3, "B": 2e-3, "c_tau": 1e-4, "c_f": 4e-3, "k_t": 0.5, "k_e": 0.5, "R": 0.5, "L": 2e-3}


def test_a_sweep_that_turns_one_way_says_it_cannot_show_an_asymmetry(tmp_path: Path,
                                                                     capsys: pytest.CaptureFixture[str]) -> None:
    forward = np.linspace(5.0, 100.0, 16)
    one_way = diagnose(load_plant(P), _sweep(forward, tmp_path / "forward.csv")).to_dict()
    assert one_way["verdict"] == []
    assert one_way["blind_spots"] == [{"gap": "reversal", "text": "the log never reverses",
                                       "hidden": ["drag_asymmetry", "thrust_asymmetry"], "design": False}]
    both = diagnose(load_plant(P), _sweep(np.concatenate([-forward[::-1], forward]), tmp_path / "both.csv"))
    assert both.verdict == [] and both.to_dict()["blind_spots"] == []
    (tmp_path / "plant.json").write_text(json.dumps(P))
    assert main(["diagnose", str(tmp_path / "forward.csv"), "--params", str(tmp_path / "plant.json"),
                 "--steady-state"]) == 0
    out = capsys.readouterr().out  # no design-experiment offered: a sweep has none
    assert "this log cannot show drag_asymmetry, thrust_asymmetry: the log never reverses\n" in out
