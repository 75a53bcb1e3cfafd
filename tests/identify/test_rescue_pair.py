"""Two effects that only together explain a log, behind a constant that wins the first round alone (session 20).

Proving-ground draw 48 (a reported seed: the case that motivated the rule, so this is a regression test, not
held-out evidence): a 1 kHz tachometer log under PI tracking and a PRBS, with a current-sensor offset of -0.47 A and
a reverse-rotation drag 43 % lower (drag asymmetry). Alone, neither effect passes its test (each leaves the other's
residual: 21.3 and 20.9 noise units); a ``c_tau`` correction wins the first round with a share of both, a false
ripple the second, and the rounds end with the torque equation at 24 noise units. Together the two effects take the
log to 1.07. Oracle: the truth of the draw; and with the rescue switched off (``RESCUE`` infinite) the verdict is
session 19's wrong one.
"""

from __future__ import annotations

import math

import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.identify import select as selection
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def _verdict() -> list[str]:
    case = make_case(48)
    assert sorted(case.expected) == ["current_offset", "drag_asymmetry"]
    return sorted(diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case)).verdict)


def test_two_overlapping_effects_start_the_rounds_again() -> None:
    assert _verdict() == ["current_offset", "drag_asymmetry"]


def test_without_the_rescue_a_constant_and_a_ripple_stood_for_them(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(selection, "RESCUE", math.inf)
    assert "drag_asymmetry" not in _verdict()
