"""Whether the log decides the ripple's period count (``angle_periodic["rivals"]``, :func:`.explain.spectrum_peak`):
the counts whose held-out share is within two standard errors of the best's. Proving-ground seeds from the validation
sets (found in session 25): 12089, a 31-period ripple at 200 Hz with a sharp spectrum, has none, and 9387, a 22-period
ripple at 1 kHz found at 7 periods on a flat spectrum (the rotor resting at a few angles), has the rig's count among
many; the CLI says so."""

from __future__ import annotations

import pytest

from bench.modelcheck import case_log
from clients.cli.answers import print_diagnosis, rivals_text
from ocp.identify import diagnose
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


@pytest.mark.parametrize(("seed", "decided"), [(12089, True), (9387, False)])
def test_a_flat_spectrum_leaves_the_count_open(seed: int, decided: bool, capsys: pytest.CaptureFixture[str]) -> None:
    case = make_case(seed)
    true = int(case.truth.effects["cogging"]["periods"])
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), case_log(case))
    ap = res.angle_periodic
    assert "cogging" in res.verdict and ap is not None
    if decided:
        assert ap["periods"] == true and ap["rivals"] == []
    else:
        assert ap["periods"] != true and true in ap["rivals"] and len(ap["rivals"]) >= 10
    print_diagnosis(res.to_dict())
    out = capsys.readouterr().out
    assert ("the count is not decided by this log" in out) is not decided


def test_rival_counts_are_printed_as_runs() -> None:
    assert rivals_text([3, 4, 5, 9]) == "3-5 and 9 periods/rev"
    assert rivals_text([7]) == "7 periods/rev"
    assert rivals_text([1, 2, 6, 7, 8, 20]) == "1, 2, 6-8 and 20 periods/rev"
