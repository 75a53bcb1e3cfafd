"""A log too slow for its electrical time constant: the check cannot resolve ``L`` at any excitation, says so and
advises the rate that can; logged at that rate, the same rig's inductance error is named (issue #11: the experiment
that settles it, where the missing evidence is the logger's rate rather than the command)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from clients.cli import main
from ocp.identify import diagnose
from ocp.identify.design import logging_advice
from ocp.logs import Log, log_from_arrays, write_log_csv
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground.experiment import at_rate, draw, run_command, voltage_steps
from tests.rig_log import rig_log

#: a proving-ground rig whose L/R is under two samples at its drawn rate (200 Hz, L/R 0.23 samples, no current
#: filter); the assertions hold for any such rig
SEED = 9
#: the inductance error hidden from the check: the rig's L is this much above the nominal the user believes
L_ERROR = 0.4


def test_the_advice_is_the_closed_form_rate_and_only_where_the_log_is_too_slow() -> None:
    p = MotorParams(J=1e-4, B=1e-5, c_tau=1e-6, c_f=1e-5, k_t=0.02, k_e=0.02, R=1.0, L=5e-4)  # L/R = 0.5 ms
    plant = DCMotorPlant(p)

    def log_at(rate: float) -> Log:
        t = np.arange(200) / rate
        v = np.sign(np.sin(2 * np.pi * 5 * t))
        return log_from_arrays(t, v, v, 0 * v, omega=50 * v)

    slow = logging_advice(plant, log_at(1000.0))  # 0.5 samples per L/R
    assert slow is not None and slow["constant"] == "L"
    assert slow["rate_hz"] == pytest.approx(4 * p.R / p.L)  # 8 kHz: four samples per L/R
    assert slow["resolves_from_hz"] == pytest.approx(2 * p.R / p.L)
    assert slow["log_rate_hz"] == pytest.approx(1000.0)
    assert "8 kHz" in slow["reason"]
    assert logging_advice(plant, log_at(3900.0)) is not None  # 1.95 samples
    assert logging_advice(plant, log_at(4100.0)) is None  # 2.05 samples: the check resolves L itself


def test_the_advised_rate_names_the_inductance_error_the_slow_log_could_not(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = draw(SEED, "coulomb_friction")
    rig.truth.effects = {}  # the inductance error alone
    nominal = dict(rig.nominal, L=rig.truth.L / (1 + L_ERROR))
    plant = DCMotorPlant(MotorParams(**nominal))
    t, v = voltage_steps(rig, SEED)

    slow = rig_log(run_command(rig, t, v, SEED + 1))
    assert rig.truth.L / rig.truth.R < 2 * slow.dt  # under two samples, by construction
    first = diagnose(plant, slow)
    assert "param:L" not in first.verdict
    advice = logging_advice(plant, slow)
    assert advice is not None
    assert f"{advice['rate_hz'] / 1e3:.3g} kHz" in first.to_dict()["calibration"]["L"]["unresolved"]
    csv, params = tmp_path / "slow.csv", tmp_path / "nominal.json"
    write_log_csv(slow, csv)
    params.write_text(json.dumps(nominal))
    assert main(["diagnose", str(csv), "--params", str(params)]) == 0  # the CLI text says it too
    assert f"logged at {advice['rate_hz'] / 1e3:.3g} kHz or faster" in capsys.readouterr().out

    fast = rig_log(run_command(at_rate(rig, advice["rate_hz"]), t, v, SEED + 1))  # the same command, logger habits
    assert logging_advice(plant, fast) is None
    second = diagnose(plant, fast)
    assert second.verdict == ["param:L"]
    assert second.to_dict()["calibration"]["L"]["relative"] == pytest.approx(L_ERROR, abs=0.05)
