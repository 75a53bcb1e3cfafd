"""A constant adopted first, before the effects that explain its part, is not named (issue #11, session 8).

Proving-ground tuning draw ``make_case(1109)`` (a tuning seed, not one of the reported 0..199): a 200 Hz tachometer
log of a rig with a force-sensor offset and a thrust asymmetry, its constants right. Taken alone, a ``c_f`` 16 %
low explains part of both (12 % of the held-out score, no materiality asked of a constant) and was adopted first;
beside the two effects adopted after it, freeing ``c_f`` no longer wins, so it is only calibrated. (On the single
held-out split: under the default cross-validation, session 11, ``c_f`` is no longer taken first on this log; the
backward pass this test pins down is the same code either way.)
"""

from __future__ import annotations

from ocp.identify import diagnose
from ocp.identify.result import DiagnoseOptions
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def test_constant_taken_first_is_dropped_beside_the_effects() -> None:
    case = make_case(1109)
    assert case.expected == {"force_offset", "thrust_asymmetry"} and not case.constant_error
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log, DiagnoseOptions(cross_validate=False))
    assert sorted(res.verdict) == ["force_offset", "thrust_asymmetry"]
    assert res.rounds[0].entries[0].name == "param:c_f"  # taken first
    assert any(e.startswith("param:c_f is not named") for e in res.explanations)
    assert not res.calibration["c_f"]["named"] and res.calibration["c_f"]["within_tolerance"]
