"""The calibrated plant's brush contact is smoothed no sharper than BRUSH_SLOPE windings (issue #11, session 14).

The catalogue's smooth contact ``v_b tanh(i / i_eps)`` has the slope ``v_b / i_eps`` [ohm] at zero current, in
series with the winding: with its default 20 mA, a 5.7 V drop is 283 ohm, an electrical mode 280 times the
winding's own, and the free run of the calibrated plant of a 50 Hz log took 61,000 RK4 steps a sample (17 s of
a 1 s diagnosis). Proving-ground seed 82, a 2.39 V brush drop named right (drawn: 2.40 V; its catalogue slope
would be 540 windings). Until session 51 the draw was ``make_case(9053)``, whose drop was false (its truth: Stribeck
friction), named beside a false ``R`` of -67 %; session 51's rules on constants a later item compensates
(``explain.pinned``, ``select._sound``) refuse that drop now, and it names the ``R`` alone.
"""

from __future__ import annotations

from ocp.identify import diagnose
from ocp.identify.explain import BRUSH_SLOPE
from ocp.logs import log_from_arrays
from ocp.logs.timebase import uniform
from ocp.model.effects import BrushDrop
from ocp.model.params import MotorParams
from ocp.model.plant import DCMotorPlant
from ocp.simulate.zoh import fastest_rate
from tests.proving_ground import make_case


def test_a_large_brush_drop_keeps_the_plant_simulable() -> None:
    case = make_case(82)
    t, c, _ = uniform(case.columns["t"], {k: v for k, v in case.columns.items() if k != "t"}, resample=True)
    log = log_from_arrays(t, c["voltage"], c["current"], c["thrust"], omega=c["omega"], theta=c.get("theta"))
    nominal = DCMotorPlant(MotorParams(**case.nominal))
    res = diagnose(nominal, log)
    brush = next(e for e in res.plant.effects if isinstance(e, BrushDrop))
    p = res.plant.params
    assert brush.v_b / BrushDrop.i_eps > 100 * p.R  # (the class: the catalogue's smoothing would be that sharp)
    assert brush.v_b / brush.i_eps <= BRUSH_SLOPE * p.R * (1 + 1e-12)
    # oracle, the Jacobian's eigenvalues (what the simulator's step rule reads): at rest the fastest mode is the
    # winding with the contact's slope in series, (R + v_b / i_eps) / L, within 1 % (the rotor's coupling)
    rate = fastest_rate(res.plant, [0.0] * len(res.plant.state_names), 0.0)
    assert rate <= 1.01 * (1 + BRUSH_SLOPE) * p.R / p.L
