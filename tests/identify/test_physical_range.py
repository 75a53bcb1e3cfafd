"""An effect fitted outside its physical range is never adopted (a crash of ``diagnose`` before, session 8).

Proving-ground draw constructed for this test (``make_case(3154, kind="constant+one")``, never the reported seeds
0..199): a log whose motor constant is wrong beside a torque ripple. A Stribeck column absorbed the residual with a
level of 1.8e4 N m; the selection adopted it and building the explained plant raised ``ParameterError`` (the
catalogue's range), so the model check crashed instead of answering.
"""

from __future__ import annotations

from ocp.identify import diagnose
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.effects import CATALOGUE, make_effect
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case


def test_an_effect_fitted_beyond_its_range_is_not_adopted_and_diagnose_answers() -> None:
    case = make_case(3154, kind="constant+one")
    assert case.expected == {"cogging", "param:k"}
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert "param:k" in res.verdict
    assert "stribeck" not in res.verdict
    for entry in (e for r in res.rounds for e in r.entries if e.significant and e.name in CATALOGUE):
        make_effect(entry.name, entry.parameters)  # every adopted effect is one the catalogue accepts

