"""A rotor that turns in reverse only: the forward drag and thrust coefficients are not in its log (issue #11: rigs
this project did not build; :func:`ocp.identify.coverage.unseen`).

The model's ``c_tau`` and ``c_f`` are forward rotation's; reverse rotation's are ``c_tau + dc_tau`` and ``c_f +
dc_f``. On a log that never turns forward the constants' columns are the asymmetries' own, so a reverse-rotation
mismatch was named as a forward constant's error the log never saw: the blind rig (``bench/blindrig``: its own physics,
loggers and PI loop, written without reading the identifier) drew two such logs, seed 151 (reverse drag 44 % high,
named ``c_tau``) and 162 (reverse thrust 31 % low, named ``c_f``). The oracles here are the proving ground's own
integrator (``tests/proving_ground``) replaying a clean rig's commands rectified to one sign, with the drawn
asymmetry or constant error, and the blind rig's two logs as drawn.
"""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.identify.coverage import SEEN_ROWS, coverage, unseen
from ocp.identify.design import design
from ocp.logs import Log, log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.effects import DragAsymmetry, load_plant
from ocp.optimize.mission import Mission
from ocp.optimize.solve import optimize
from tests.proving_ground import make_case
from tests.proving_ground.cases import replay
from tests.proving_ground.experiment import Rig, run_command
from tests.rig_log import rig_log

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

from blindrig.draw import draw_case
from blindrig.logger import run_log


def _one_way(seed: int, sign: float, effects: dict[str, dict[str, float]], c_tau: float = 1.0) -> tuple[dict, Log]:
    """Proving-ground clean case ``seed``'s rig and logger under its commands rectified to ``sign`` (the rotor turns
    one way only), with ``effects`` and its drag coefficient ``c_tau`` times the drawn one; (nominal, log)."""
    case = make_case(seed, kind="clean")
    cols = replay(case, sign * np.abs(case.columns["voltage"]), np.random.default_rng(seed), effects=effects,
                  c_tau=case.truth.c_tau * c_tau)
    return case.nominal, case_log(dataclasses.replace(case, columns=cols))


def _read(cols: dict[str, np.ndarray]) -> Log:
    """The logged columns as the file readers give them (jittery time stamps resampled to a uniform grid)."""
    t, x, _ = uniform(cols["t"], {k: v for k, v in cols.items() if k in ("voltage", "current", "thrust", "omega",
                                                                         "theta")}, resample=True)
    return log_from_arrays(t, x["voltage"], x["current"], x["thrust"], omega=x.get("omega"), theta=x.get("theta"))


@pytest.mark.parametrize("seed", [2, 3, 4, 5])
def test_a_reverse_drag_is_the_asymmetry_at_its_drawn_size(seed: int) -> None:
    c_tau = make_case(seed, kind="clean").truth.c_tau
    nominal, log = _one_way(seed, -1.0, {"drag_asymmetry": {"dc_tau": 0.4 * c_tau}})
    d = diagnose(load_plant(nominal), log)
    assert d.verdict == ["drag_asymmetry"], d.verdict
    (asym,) = [e for e in d.plant.effects if e.name == "drag_asymmetry"]
    assert isinstance(asym, DragAsymmetry)
    assert asym.dc_tau / c_tau == pytest.approx(0.4, abs=0.03)  # all of it: the forward constant held at nominal
    assert d.plant.params.c_tau == pytest.approx(nominal["c_tau"])
    assert "never turns forward" in d.calibration["c_tau"]["unresolved"]
    assert any(s["gap"] == "forward" and "param:c_tau" in s["hidden"] for s in d.blind_spots)
    assert all("thrust_asymmetry" not in s["hidden"] for s in d.blind_spots)  # (reverse rotation shows it)


def test_a_wrong_drag_coefficient_is_the_ambiguity_and_a_forward_run_settles_it() -> None:
    """``c_tau`` 40 % high in both directions, logged in reverse only: one column with the asymmetry, so the verdict
    names the asymmetry (the nominal value is forward rotation's) and lists ``param:c_tau`` as ambiguous with the
    reason; the experiment designed for it, optimised within the limits and played on the same rig (the proving
    ground's own integrator), turns forward and names the constant."""
    nominal, log = _one_way(3, -1.0, {}, c_tau=1.4)
    plant = load_plant(nominal)
    first = diagnose(plant, log)
    assert first.verdict == ["drag_asymmetry"], first.verdict
    (amb,) = [a for a in first.ambiguous if a["alternative"] == "param:c_tau"]
    assert amb["adopted"] == "drag_asymmetry" and "never turns forward" in amb["reason"]
    case = make_case(3, kind="clean")
    rig = Rig(dataclasses.replace(case.truth, c_tau=1.4 * case.truth.c_tau), case.logger, case.meta["tau_m"], nominal)
    proposal = design(plant, log, first)
    assert proposal.mission is not None and {"param:c_tau", "drag_asymmetry"} <= {
        i for r in proposal.rivals for i in r.items}
    res = optimize(Mission.model_validate(proposal.mission))
    assert res.source == "optimized" and res.path_ok
    new = rig_log(run_command(rig, res.arrays["t"], res.arrays["voltage"], 10))
    assert coverage(new)["forward"]
    second = diagnose(plant, new)
    assert second.verdict == ["param:c_tau"], second.verdict


def test_a_small_reverse_mismatch_is_calibrated_not_named() -> None:
    """5 % (within the 10 % tolerance): the nominal value's own error, no asymmetry."""
    nominal, log = _one_way(2, -1.0, {}, c_tau=1.05)
    d = diagnose(load_plant(nominal), log)
    assert d.verdict == [], d.verdict
    assert d.calibration["c_tau"]["relative"] == pytest.approx(0.05, abs=0.02)


def test_a_forward_only_log_still_names_the_constant() -> None:
    """The rule is one-sided: forward rotation shows ``c_tau`` itself (40 % off), and no asymmetry can show."""
    nominal, log = _one_way(3, 1.0, {}, c_tau=1.4)
    d = diagnose(load_plant(nominal), log)
    assert d.verdict == ["param:c_tau"], d.verdict
    assert d.calibration["c_tau"]["relative"] == pytest.approx(0.4, abs=0.03)
    assert not d.calibration["c_tau"]["unresolved"]
    assert any(s["gap"] == "reversal" and "drag_asymmetry" in s["hidden"] for s in d.blind_spots)


@pytest.mark.parametrize("seed", [151, 162])
def test_the_blind_rigs_reverse_only_logs_name_their_asymmetry(seed: int) -> None:
    case = draw_case(seed)
    cols = run_log(case.truth, case.cfg, case.exc, case.h_max, np.random.default_rng([seed, 7]), case.theta0)
    assert cols["true_w"].max() <= 0.0 < -cols["true_w"].min()  # (as drawn: reverse rotation only)
    drop = {"omega": "theta", "theta": "omega", "both": ""}[case.cfg.columns]  # (the columns its logger exports)
    d = diagnose(load_plant(case.nominal), _read({k: v for k, v in cols.items() if k != drop}))
    assert d.verdict == case.labels and case.labels[0].endswith("asymmetry"), (d.verdict, case.labels)


def test_the_rule_needs_reverse_rotation_and_no_forward_rows() -> None:
    t = 1e-3 * np.arange(2000)
    ones = np.ones_like(t)

    def log_of(w: np.ndarray) -> Log:
        return log_from_arrays(t, ones, ones, ones, omega=w)

    rev = -100.0 * np.abs(np.sin(t))
    assert set(unseen(log_of(rev))) == {"c_tau", "c_f"}
    assert not coverage(log_of(rev))["forward"]
    assert unseen(log_of(-rev)) == {}  # forward only
    assert unseen(log_of(100.0 * np.sin(3.0 * t))) == {}  # both ways
    assert unseen(log_of(np.zeros_like(t))) == {}  # never turning: nothing to say about either direction
    few = rev.copy()
    few[: int(2 * SEEN_ROWS * t.size)] = 50.0  # forward on twice the rows the rule asks
    assert unseen(log_of(few)) == {}
