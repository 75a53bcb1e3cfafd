"""Effects in the model check: a shape between grid points, and two effects that show only together.

Each test is a log on which the previous selection was wrong (session 6, issue #11): a wake lag between two grid
points left a residual that a wrong ``c_f`` took up (its fitted lag 25 % off), and an angle ripple beside Coulomb
friction on a short 10 kHz log was not named at all (each alone fitted into the other's residual).
"""

from __future__ import annotations

import pytest

from ocp.identify import diagnose
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from tests.proving_ground import make_case
from tests.synthetic_rig import RigSpec, generate


def test_a_wake_lag_between_grid_points_is_fitted_there(rig: MotorParams) -> None:
    """0.045 s lies between the lag grid's 0.034 and 0.060 s: the two neighbouring columns' mix fits it."""
    log = generate(rig, RigSpec(effects={"thrust_lag": {"tau": 0.045}}, seconds=1.5, seed=11))
    res = diagnose(DCMotorPlant(rig), log)
    assert res.verdict == ["thrust_lag"]
    assert res.ranking[0].name == "thrust_lag"
    assert res.ranking[0].parameters["tau"] == pytest.approx(0.045, rel=0.12)  # one grid column: 0.034 (-25 %)


def test_angle_ripple_and_coulomb_friction_are_named_together() -> None:
    """Proving-ground draw 1070 (a tuning seed: a 5 W motor, 10 kHz tachometer log of 0.6 s, chirp and sweep):
    18-period ripple of 23 mN m and 8.6 mN m of Coulomb friction. The torque rows of so short and fast a log are
    few independent ones; neither effect alone clears the sampling scatter, the two together explain the torque
    residual down to the noise."""
    case = make_case(1070)
    assert case.expected == {"cogging", "coulomb_friction"}
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert set(res.verdict) == {"cogging", "coulomb_friction"}
    assert res.angle_periodic is not None and res.angle_periodic["periods"] == 18
    friction = next(e for r in res.rounds for e in r.entries if e.name == "coulomb_friction" and e.significant)
    assert friction.parameters["tau_c"] == pytest.approx(case.truth.e("coulomb_friction", "tau_c"), rel=0.25)
