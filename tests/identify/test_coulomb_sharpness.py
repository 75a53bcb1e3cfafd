"""Coulomb friction is a sign, as sharp as the rig's: its smoothing width is fitted on a grid (issue #11, session 15).

Dry friction holds the rotor at rest while the motor torque stays within ``+-tau_c``; a rig's rotor dwells there at
speeds far under the catalogue's 0.5 rad/s smoothing (which is set for the optimiser). Fitted with that smoothing,
every dwell left a torque residual that an angle ripple of some period count then took up: on proving-ground draws
``make_case(10152)`` and ``make_case(9213)`` (session 15's fresh seeds, no longer untouched) Coulomb friction alone
was named with cogging. The calibrated plant keeps the fitted sign only as sharp as ``FRICTION_SLOPE`` times the
motor's own damping (a free run or the optimiser would resolve a sharper one at thousands of steps a sample).
"""

from __future__ import annotations

import pytest

from ocp.identify import diagnose
from ocp.identify.explain import FRICTION_SLOPE
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.effects import CoulombFriction
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.simulate.zoh import fastest_rate
from tests.proving_ground import make_case


@pytest.mark.parametrize("seed", [10152, 9213])
def test_coulomb_friction_alone_is_named_alone_at_its_level(seed: int) -> None:
    case = make_case(seed)
    assert set(case.truth.effects) == {"coulomb_friction"} and not case.constant_error  # (the premise)
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    res = diagnose(DCMotorPlant(MotorParams(**case.nominal)), log)
    assert res.verdict == ["coulomb_friction"]
    fitted = res.ranking[0]
    assert fitted.name == "coulomb_friction"
    assert fitted.parameters["tau_c"] == pytest.approx(case.truth.e("coulomb_friction", "tau_c"), rel=0.05)
    # the calibrated plant's sign: the fitted width, or wider where that is sharper than FRICTION_SLOPE allows
    friction = next(e for e in res.plant.effects if isinstance(e, CoulombFriction))
    assert friction.omega_eps >= fitted.parameters["omega_eps"]
    p = res.plant.params
    damping = p.k_t * p.k_e / p.R  # [N m s/rad]
    assert friction.tau_c / friction.omega_eps <= FRICTION_SLOPE * damping * (1 + 1e-12)
    # oracle, the Jacobian's eigenvalues at rest (what the simulator's step rule reads): no mode faster than the
    # armature's and the rotor's with the friction's slope added to its damping, (D + tau_c / omega_eps) / J
    rate = fastest_rate(res.plant, [0.0] * len(res.plant.state_names), 0.0)
    assert rate <= 1.01 * max(p.R / p.L, (1 + FRICTION_SLOPE) * damping / p.J + p.R / p.L)
