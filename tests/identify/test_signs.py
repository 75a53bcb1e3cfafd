"""A channel logged with the opposite sign (:mod:`ocp.identify.signs`): proving-ground rigs (their own integrator and
formulas) with one channel negated after the fact are refused by ``diagnose``, ``check`` and ``fit``, the error
naming that channel; read back with ``negate`` (the CLI's ``--negate``, the API's form field) they are diagnosed as
the rig they are. Before, a negated current came back as a brush drop, ``J`` and a dead band at 100-800 noise
units. The logs as drawn are never refused (``bench/sign_conventions.py`` over 600 of them; every other test of a
time series here is a further case)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from clients.cli import main
from ocp.errors import LogError
from ocp.identify import check, diagnose, fit
from ocp.identify.signs import negated as found
from ocp.identify.signs import scales
from ocp.logs import ReadOptions, negated, read_log, write_log_csv
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from service.modelcheck import parse_read
from tests.proving_ground.experiment import Rig, draw, run_command, voltage_steps
from tests.rig_log import rig_log

CHANNELS = ("current", "omega", "thrust", "voltage")


def _rig(seed: int) -> tuple[Rig, dict[str, np.ndarray]]:
    rig = draw(seed, "coulomb_friction")  # its friction hidden: the verdict to find once the sign is right
    t, v = voltage_steps(rig, seed)
    return rig, run_command(rig, t, v, seed + 1)


@pytest.mark.parametrize("seed", [3, 5])
def test_a_negated_channel_is_refused_naming_it(seed: int) -> None:
    rig, cols = _rig(seed)
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    log = rig_log(cols)
    # the oracle: a rig drawn with exact nominal constants scales each equation's terms by about one
    assert all(abs(b - 1.0) < 0.1 for b in scales(plant, log).values())
    assert found(plant, log) == {}
    for ch in CHANNELS:
        bad = negated(log, [ch])
        assert list(found(plant, bad)) == [ch]
        for op in (lambda lg: diagnose(plant, lg), lambda lg: check(plant, lg), lambda lg: fit(plant, lg, ["param:B"])):
            with pytest.raises(LogError) as err:
                op(bad)
            assert err.value.field == ch and f"--negate {ch}" in err.value.reason


def test_negate_reads_the_channel_back(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig, cols = _rig(3)
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    csv, params = tmp_path / "flipped.csv", tmp_path / "nominal.json"
    write_log_csv(rig_log(dict(cols, current=-cols["current"])), csv)
    params.write_text(json.dumps(rig.nominal))
    assert main(["diagnose", str(csv), "--params", str(params)]) != 0
    assert "current: logged with the opposite sign" in capsys.readouterr().err
    assert main(["diagnose", str(csv), "--params", str(params), "--negate", "current"]) == 0
    out = capsys.readouterr().out
    assert "read: negated as asked: current" in out
    log = read_log(csv, options=ReadOptions(negate=("current",)))
    assert np.allclose(log.current, rig_log(cols).current)  # (the CSV round trip)
    assert diagnose(plant, log).verdict == diagnose(plant, rig_log(cols)).verdict


def test_negated_turns_the_angle_with_the_speed_and_says_so() -> None:
    t = np.arange(50) * 1e-3
    log = rig_log({"t": t, "voltage": np.ones(50), "current": np.ones(50), "thrust": np.ones(50),
                   "omega": np.full(50, 10.0), "theta": 10.0 * t})
    out = negated(log, ["omega"])
    assert np.array_equal(out.omega, -log.omega) and out.theta is not None and np.array_equal(out.theta, -10.0 * t)
    assert np.array_equal(out.current, log.current) and out.notes[-1] == "negated as asked: omega"
    assert negated(log, []) is log


def test_the_api_field_is_comma_separated_and_checked() -> None:
    assert parse_read(negate="current, thrust") == {"negate": ["current", "thrust"]}
    with pytest.raises(LogError) as err:
        parse_read(negate="curent")
    assert err.value.field == "negate"
