"""Model check on a synthetic rig: check at the noise floor on clean data, diagnose names every hidden
catalogue effect first and halves the affected channel's held-out error, finds two at once, says
"nothing missing" on clean data; diagnose -> fit -> calibrated file -> load_plant -> optimize."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from clients.cli import main
from ocp.identify import DiagnoseOptions, check, diagnose, fit
from ocp.identify.check import CheckResult
from ocp.identify.predict import CHANNELS
from ocp.identify.report import html_report
from ocp.logs import Log, write_log_csv
from ocp.model.effects import load_plant
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.model.test_effects import VALUES
from tests.synthetic_rig import RigSpec, generate

SECONDS = 1.5  # per excitation: sine, sin^5, chirp -> 4.5 s at 1 kHz


@pytest.fixture(scope="module")
def clean(rig: MotorParams) -> Log:
    return generate(rig, RigSpec(seconds=SECONDS, seed=0))


def test_check_on_clean_data_is_at_the_sensor_noise(rig: MotorParams, clean: Log) -> None:
    spec = RigSpec()
    res = check(DCMotorPlant(rig), clean)
    assert isinstance(res, CheckResult)  # a time series' check (a sweep's is a PointCheck)
    for ch, sigma in (("omega", spec.noise_omega), ("current", spec.noise_current), ("thrust", spec.noise_thrust)):
        assert 0.8 * sigma < res.free_run_rms[ch] < 1.3 * sigma, ch
    d = json.loads(json.dumps(res.to_dict(), allow_nan=False))
    assert set(d["breakdown"]) == {"direction", "speed band", "reversal", "acceleration", "rotor angle"}
    assert d["correlation"]["band"] == pytest.approx(1.96 / np.sqrt(clean.n - 1))
    page = html_report(res, clean)
    assert page.count("data:image/png;base64,") == 4 and "http" not in page.split("<body>")[1]


def test_check_shows_coulomb_friction_by_direction(rig: MotorParams) -> None:
    """The signature of dry friction: a mean torque residual (measured - model) against the speed's sign."""
    log = generate(rig, RigSpec(effects={"coulomb_friction": {"tau_c": 0.003}}, seconds=SECONDS, seed=4))
    b = check(DCMotorPlant(rig), log).breakdown["direction"]
    assert b["thrust >= 0"]["one_step_mean.mechanical"] < -0.002
    assert b["thrust < 0"]["one_step_mean.mechanical"] > 0.002


def test_clean_data_nothing_missing(rig: MotorParams, clean: Log) -> None:
    res = diagnose(DCMotorPlant(rig), clean)
    assert res.verdict == []
    d = res.to_dict()
    assert d["message"] == "nothing missing" and not any(e["significant"] for e in d["ranking"])


@pytest.mark.parametrize("name", sorted(VALUES))
def test_diagnose_names_the_hidden_effect_first(name: str, rig: MotorParams) -> None:
    log = generate(rig, RigSpec(effects={name: VALUES[name]}, seconds=SECONDS, seed=1))
    res = diagnose(DCMotorPlant(rig), log, DiagnoseOptions(max_effects=1))
    assert res.verdict == [name]
    top, base = res.ranking[0], res.rounds[0].baseline
    assert top.name == name and top.significant
    # the affected channel = the one furthest above its noise level; held-out error at least halved
    worst = max(CHANNELS, key=lambda ch: base.rms[ch] / res.noise[ch])
    assert top.heldout_rms[worst] <= 0.5 * base.rms[worst]
    for key, true in VALUES[name].items():
        if key in top.parameters and true != 0:
            assert top.parameters[key] == pytest.approx(true, rel=0.25), key


@pytest.mark.slow
def test_two_hidden_effects_are_both_found(rig: MotorParams) -> None:
    effects = {"coulomb_friction": VALUES["coulomb_friction"], "thrust_lag": VALUES["thrust_lag"]}
    log = generate(rig, RigSpec(effects=effects, seconds=SECONDS, seed=2))
    res = diagnose(DCMotorPlant(rig), log)
    assert set(res.verdict) == set(effects)
    assert len(res.rounds) == 3 and not res.rounds[-1].entries[0].significant  # then nothing more


@pytest.mark.slow
def test_diagnose_fit_optimize_round_trip(rig: MotorParams, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    log = generate(rig, RigSpec(effects={"brush_drop": VALUES["brush_drop"]}, seconds=SECONDS, seed=3))
    csv = tmp_path / "rig.csv"
    write_log_csv(log, csv)
    assert main(["diagnose", str(csv), "--params", "paper-rig", "--json"]) == 0
    verdict = json.loads(capsys.readouterr().out)["verdict"]
    assert verdict == ["brush_drop"]
    out = tmp_path / "calibrated.json"
    assert main(["fit", str(csv), "--params", "paper-rig", "--effects", ",".join(verdict), "--json",
                 "--out", str(out)]) == 0
    report = json.loads(capsys.readouterr().out)
    assert report["rms_after"]["omega"] < 0.1 * report["rms_before"]["omega"]
    plant = load_plant(out)
    assert [e.name for e in plant.effects] == ["brush_drop"]
    assert plant.effects[0].v_b == pytest.approx(0.3, rel=0.05)  # type: ignore[attr-defined]
    again = fit(DCMotorPlant(rig), log, verdict)
    assert again.plant == plant
    checked = check(plant, log)
    assert isinstance(checked, CheckResult) and checked.free_run_rms["omega"] < 1.3 * RigSpec().noise_omega
    from ocp.optimize.mission import mission_from_mapping
    from ocp.optimize.solve import optimize

    mission = mission_from_mapping({"params": json.loads(out.read_text()), "segments": [
        {"kind": "hold", "duration": 0.3, "thrust": 0.3}, {"kind": "reversal", "duration": 0.6, "to": -0.3},
        {"kind": "hold", "duration": 0.3, "thrust": -0.3}], "collocation": {"intervals": 60}, "time_limit_s": 20})
    result = optimize(mission)
    assert result.source == "optimized", result.reason
    # the calibrated reference is what the rig's true plant does under its command; the nominal one is not
    from tests.optimize.test_optimize_effects import _true_error

    truth = load_plant({**rig.model_dump(), "effects": {"brush_drop": VALUES["brush_drop"]}})
    nominal = optimize(mission_from_mapping({**mission.model_dump(mode="json"), "params": "paper-rig"}))
    assert _true_error(result, truth) <= 2e-3 * 0.3
    assert _true_error(result, truth) <= 0.25 * _true_error(nominal, truth)


def test_cli_errors_exit_1(tmp_path: Path, clean: Log, capsys: pytest.CaptureFixture[str]) -> None:
    csv = tmp_path / "clean.csv"
    write_log_csv(clean, csv)
    assert main(["fit", str(csv), "--params", "paper-rig", "--effects", "warp_drive"]) == 1
    assert "warp_drive" in capsys.readouterr().err
    assert main(["check", str(tmp_path / "missing.csv"), "--params", "paper-rig"]) == 1
