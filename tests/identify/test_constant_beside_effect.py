"""A wrong constant beside a real effect is named, not absorbed: for a constant the tolerance is the materiality
(beyond it the user wants the name), so freeing it must win on held-out data beyond sampling noise, not by the
12 % an effect must bring (a drag coefficient 15 % off beside a thrust asymmetry or a force-sensor offset moves
the score by less: calibration takes the first 10 %)."""

from __future__ import annotations

import pytest

from ocp.identify import diagnose
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.synthetic_rig import RigSpec, generate


def test_a_wrong_drag_coefficient_beside_an_effect_is_named(rig: MotorParams) -> None:
    effect = "thrust_asymmetry"
    log = generate(rig, RigSpec(effects={effect: {"dc_f": -0.2 * rig.c_f}}, seconds=1.5, seed=11))
    nominal = rig.model_copy(update={"c_tau": rig.c_tau / 1.15})  # true c_tau = nominal x 1.15
    res = diagnose(DCMotorPlant(nominal), log)
    assert sorted(res.verdict) == sorted([effect, "param:c_tau"])
    cal = res.calibration["c_tau"]
    assert cal["named"] and cal["fitted"] == pytest.approx(rig.c_tau, rel=0.05)
