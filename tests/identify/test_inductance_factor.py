"""An inductance error beyond a factor two is left unresolved where the command timing was measured too (issue #11: rigs
this project did not build; the prior on constant errors, :data:`ocp.identify.evidence.IMPLAUSIBLE_FACTOR`).

Under an open timing (no alignment found) the rule was in already. With the timing measured, the blind rig's fresh
seed 357 (``bench/blindrig``: its own simulator; a clean 1.15 kHz log of a slow ramp, L/R 5.7 samples, its command
logged a sample early and aligned at none) came back with ``L`` 80 % low, at its box: a smooth command lets a timing
error of the command or the current's sensor pass for a shorter L/R, and an inductance five times off its datasheet
is the less likely error. The controls: the proving ground's seeds 55 and 103, whose ``L`` drawn within the factor
(+24 % at 10 kHz, -14 % at 1 kHz) is still named, at its size.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from bench.modelcheck import case_log
from ocp.identify import diagnose
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.identify.diagnosed import blind
from tests.proving_ground import make_case


def test_an_inductance_beyond_a_factor_two_is_not_named_on_a_clean_log(tmp_path: Path) -> None:
    d, _ = blind(357, tmp_path)
    assert d.verdict == [], d.verdict
    cal = d.calibration["L"]
    assert cal["apparent"] < -0.5 and not cal["named"]  # (the fit that was named: beyond the factor)
    assert "more than a factor two" in cal["unresolved"] and "not identifiable" not in cal["unresolved"]
    assert d.alignment is not None and d.alignment.identified  # (the timing measured: the rule's new ground)


@pytest.mark.parametrize("seed", [55, 103])
def test_an_inductance_error_within_the_factor_is_still_named(seed: int) -> None:
    case = make_case(seed)
    d = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    assert d.verdict == ["param:L"], d.verdict
    assert d.calibration["L"]["relative"] == pytest.approx(case.constant_error["L"], abs=0.1)
