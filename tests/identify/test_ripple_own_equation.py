"""An angle ripple is judged on the torque equation it enters, whatever that equation's noise units read (issue #11:
logs nobody here generated; :func:`ocp.identify.evidence.own_material`, :func:`ocp.identify.select._halves`).

The noise level of an equation is an estimate. On the blind rig (``bench/blindrig``: its own integrator, effect
formulas and loggers, written without reading the identifier) the torque equation of a clean-sensing 5 kHz log read
0.68 noise units before its 18-period ripple was fitted and 0.18 after: a fall of 73 % that the materiality with the
other equations counted at the noise level saw as 8 %. On another log a brush drop left every equation under one noise
unit, and the rounds stopped with a ripple that took the torque equation from 0.65 to 0.23 unexplained.

Oracles (the closed-form unit test is in ``test_materiality_capped.py``): the blind rig's fresh seeds 368 and 227
(its truth files: an 18-period ripple; a brush drop and an 18-period ripple), regenerated here. The control is
proving-ground tuning seed 1157, a clean log whose best ripple wins by its own test alone (a fast ripple's
independent rows) with a 17 % fall of the torque equation: it stays unnamed, since the own-equation materiality holds
only beside a win beyond the pooled scatter or by the likelihood ratio (allowed by its own test too, it named that
ripple: tried).
"""

from __future__ import annotations

from pathlib import Path

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.identify.diagnosed import blind
from tests.proving_ground import make_case


def test_a_ripple_under_the_torque_noise_level_is_named(tmp_path: Path) -> None:
    d = blind(368, tmp_path)[0]
    assert d.verdict == ["cogging"], d.verdict
    assert d.angle_periodic is not None and d.angle_periodic["periods"] == 18
    entry = d.rounds[0].entries[0]
    assert entry.name == "cogging" and entry.significant and entry.improvement < 0.12  # (the pooled fall: 8 %)
    assert "The torque equation's held-out error falls 73 % (0.68 -> 0.18 noise units)" in entry.explanation


def test_a_ripple_halving_the_torque_error_is_named_with_every_equation_at_the_floor(tmp_path: Path) -> None:
    d = blind(227, tmp_path)[0]
    assert sorted(d.verdict) == ["brush_drop", "cogging"], d.verdict
    assert d.angle_periodic is not None and d.angle_periodic["periods"] == 18


def test_a_ripple_winning_by_its_own_test_alone_stays_held_to_the_pooled_fall() -> None:
    case = make_case(1157)
    assert case.expected == set()
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert res.verdict == [], res.verdict
