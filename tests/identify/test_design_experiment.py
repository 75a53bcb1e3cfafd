"""Design the experiment that settles it (issue #11 item 5): a proving-ground log where Coulomb friction
and a drag change look alike (one operating speed) is turned into the right verdict by running the proposed
mission on the same rig. The rig, its logger and its integrator are the proving ground's (no ``ocp`` code)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from clients.cli import main
from ocp.errors import SolverError
from ocp.identify import diagnose
from ocp.identify.coverage import RIPPLE_ROWS, coverage
from ocp.identify.design import DesignOptions, confusion, design
from ocp.identify.separation import simulate, with_effect
from ocp.logs import write_log_csv
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.optimize.mission import Mission
from ocp.optimize.solve import optimize
from tests.proving_ground.experiment import draw, run_command, single_speed, voltage_steps
from tests.rig_log import rig_log

SEED = 6  # any rig whose single-speed log the identifier does not settle; the assertions hold whatever it is
#: the command's wobble around the one speed [fraction]: at 8 % the identifier separates Coulomb friction from a
#: drag change by the speed steps alone; at 2 % the log cannot tell them apart
SWING = 0.02


def test_the_proposed_experiment_turns_an_ambiguous_verdict_into_the_right_one(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = draw(SEED, "coulomb_friction")
    log = rig_log(single_speed(rig, SEED, swing=SWING))
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    first = diagnose(plant, log)
    cov = coverage(log)
    assert not cov["reversal"] and not cov["low_speed"]  # one operating speed, by construction
    assert first.ambiguous or first.verdict != ["coulomb_friction"], "the single-speed log already settles it"

    csv, params, out = tmp_path / "rig.csv", tmp_path / "rig.json", tmp_path / "mission.json"
    write_log_csv(log, csv)
    params.write_text(json.dumps(rig.nominal))
    current = 3.0 * float(np.max(np.abs(log.current)))
    assert main(["design-experiment", str(csv), "--params", str(params), "--voltage", str(rig.truth.v_max),
                 "--current", str(current), "--out", str(out), "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["needed"] and d["mission"] == json.loads(out.read_text())
    assert "coulomb_friction" in {i for r in d["rivals"] for i in r["items"]}
    # the proposal separates every pair of rivals better than the log did, and says how well
    chosen = d["chosen"]["separation"]
    assert set(chosen) == set(d["current_log_separation"])
    assert min(chosen.values()) > min(d["current_log_separation"].values())
    assert d["separation"] == pytest.approx(min(chosen.values()))
    assert d["misclassification"] == pytest.approx(confusion(d["separation"])) and d["misclassification"] < 0.05

    # the mission runs in the optimiser within the limits
    res = optimize(Mission.model_validate(json.loads(out.read_text())))
    assert res.source == "optimized" and res.path_ok
    assert np.max(np.abs(res.arrays["current"])) <= current * (1 + 1e-6)
    assert np.max(np.abs(res.arrays["voltage"])) <= rig.truth.v_max * (1 + 1e-6)
    # played on the same rig (the proving ground's own simulation of the command), the new log settles it
    new = rig_log(run_command(rig, res.arrays["t"], res.arrays["voltage"], SEED + 7))
    assert coverage(new)["reversal"]
    second = diagnose(plant, new)
    assert second.verdict == ["coulomb_friction"] and not second.ambiguous


def test_design_refuses_what_it_cannot_use(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    rig = draw(SEED, "coulomb_friction")
    csv = tmp_path / "rig.csv"
    write_log_csv(rig_log(single_speed(rig, SEED)), csv)
    assert main(["design-experiment", str(csv), "--params", "paper-rig", "--rival", "coulomb_friction",
                 "--json"]) == 1
    err = json.loads(capsys.readouterr().err)
    assert err["field"] == "--rival" and "two" in err["reason"]
    assert main(["design-experiment", str(csv), "--params", "paper-rig", "--rival", "coulomb_friction",
                 "--rival", "no_such_effect", "--json"]) == 1
    assert "no_such_effect" in json.loads(capsys.readouterr().err)["reason"]
    assert main(["design-experiment", str(csv), "--params", "paper-rig", "--voltage", "-3", "--json"]) == 1
    assert json.loads(capsys.readouterr().err)["field"] == "--voltage"


#: a rig with an angle ripple of 20 periods/rev logged at 200 Hz (any rig whose single-speed log resolves fewer counts
#: than its ripple's; the assertions hold whatever it is)
RIPPLE_SEED = 0


def test_a_ripple_beyond_the_logs_reach_is_probed_and_the_proposal_reveals_it() -> None:
    """Near one speed the log resolves a few counts per revolution: the ripple averages out within a sample and the
    check names nothing. The design takes the lack of rows slow enough for a 64-period ripple as a coverage gap (a
    ripple probed at that count), and the proposed command, played on the same rig, shows the ripple with the rig's
    count."""
    rig = draw(RIPPLE_SEED, "cogging")
    count = rig.truth.effects["cogging"]["periods"]
    log = rig_log(single_speed(rig, RIPPLE_SEED))
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    first = diagnose(plant, log)
    cov = coverage(log)
    # the reach and the slow rows against the closed forms on the logged angle: pi / median step, 64 step < pi
    step = np.abs(np.diff(log.theta if log.theta is not None else np.cumsum(log.omega) * log.dt))
    moving = step[step > 0]
    assert cov["ripple_periods"] == int(np.pi / np.median(moving)) < count
    assert cov["ripple_rows"] == pytest.approx(np.mean(64 * moving < np.pi))
    assert cov["ripple_rows"] < RIPPLE_ROWS and not cov["ripple_reach"]
    assert "cogging" not in first.verdict
    d = design(plant, log, first, DesignOptions(voltage=rig.truth.v_max,
                                                current=3.0 * float(np.max(np.abs(log.current))))).to_dict()
    probe = "diagnosed plant vs cogging (probe)"
    assert f"at most {cov['ripple_periods']} periods/rev" in " ".join(d["reasons"])
    # and its L/R is under two samples at 200 Hz: the design says so, with the closed-form rate (four per L/R)
    assert rig.nominal["L"] / rig.nominal["R"] < 2 * log.dt
    assert d["logging"]["rate_hz"] == pytest.approx(4 * rig.nominal["R"] / rig.nominal["L"])
    assert d["logging"]["reason"] in d["reasons"]
    assert d["chosen"]["separation"][probe] > d["current_log_separation"][probe]
    res = optimize(Mission.model_validate(d["mission"]))
    new = rig_log(run_command(rig, res.arrays["t"], res.arrays["voltage"], RIPPLE_SEED + 7))
    assert coverage(new)["ripple_reach"]  # the gap closes once the experiment is logged
    second = diagnose(plant, new)
    assert "cogging" in second.verdict and second.angle_periodic is not None
    assert second.angle_periodic["periods"] == count


def test_a_probe_the_free_run_cannot_simulate_is_left_out_with_its_reason() -> None:
    """Proving-ground rig 17 logged near one speed at 200 Hz: the 3 % brush-drop probe's contact (``tanh(i / i_eps)``
    at zero current) needs more RK4 steps a sample than the free run takes, from rest, where every proposal starts.
    The design used to fail on it as a whole; it leaves that probe out, says why, and proposes a run for the rest."""
    rig = draw(17, "cogging")
    log = rig_log(single_speed(rig, 17))
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    res = design(plant, log, diagnose(plant, log),
                 DesignOptions(voltage=rig.truth.v_max, current=3.0 * float(np.max(np.abs(log.current)))))
    d = res.to_dict()
    left = [r for r in d["reasons"] if "left out" in r]
    assert len(left) == 1 and left[0].startswith("brush_drop (probe) left out")
    assert "brush_drop (probe)" not in [r["name"] for r in d["rivals"]] and d["mission"] is not None
    # the reason is the free run's own: the probe plant, simulated from rest at the log's rate, is refused
    brush = with_effect(res.rivals[0].plant, "brush_drop", {"v_b": 0.03 * rig.truth.v_max})
    with pytest.raises(SolverError, match="too stiff"):
        simulate(brush, log.t[:50], np.full(50, 1.0))


#: a rig with a hidden voltage dead band, logged at 200 Hz (any rig whose two-level log misses its dead band; the
#: assertions hold whatever it is)
LEVELS_SEED = 0


def test_a_dead_band_a_two_level_command_hides_is_probed_and_the_proposal_reveals_it() -> None:
    """Under random steps between +-0.6 V_max the dead band's ``V0 - v_db`` is a gain on the command, which the
    constants take up: the check names ``R`` instead. The design takes the one voltage magnitude as a coverage gap
    (dead band and brush drop probed), and the proposed command, played on the same rig, shows the dead band."""
    rig = draw(LEVELS_SEED, "voltage_deadband")
    t, v = voltage_steps(rig, LEVELS_SEED, levels=(-1.0, 1.0))
    log = rig_log(run_command(rig, t, v, LEVELS_SEED + 1))
    plant = DCMotorPlant(MotorParams(**rig.nominal))
    first = diagnose(plant, log)
    cov = coverage(log)
    on = np.abs(log.voltage)[np.abs(log.voltage) > 0.01 * np.max(np.abs(log.voltage))]
    assert cov["voltage_spread"] == pytest.approx(np.percentile(on, 10) / np.percentile(on, 90))
    assert not cov["voltage_range"] and "voltage_deadband" not in first.verdict
    d = design(plant, log, first, DesignOptions(voltage=rig.truth.v_max,
                                                current=3.0 * float(np.max(np.abs(log.current))))).to_dict()
    assert any("one voltage magnitude" in r for r in d["reasons"])
    names = {r["name"] for r in d["rivals"]}
    assert "voltage_deadband (probe)" in names
    assert "brush_drop (probe)" in names or any(r.startswith("brush_drop (probe) left out") for r in d["reasons"])
    res = optimize(Mission.model_validate(d["mission"]))
    new = rig_log(run_command(rig, res.arrays["t"], res.arrays["voltage"], LEVELS_SEED + 7))
    assert coverage(new)["voltage_range"]  # the gap closes once the experiment is logged
    assert "voltage_deadband" in diagnose(plant, new).verdict
