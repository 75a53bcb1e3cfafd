"""The analytic fallback never answers over its limits (issue #12, finding 2).

Adversarial missions -- hundreds of reversals, long fast sines, tiny current limits, a friction the
closed forms leave out, the torque channel -- go through :func:`ocp.reference.fallback_answer.analytic_fallback`. Each
answer is either an :class:`~ocp.errors.InfeasibleError` naming a limit, or a reference whose simulated
response stays within every limit on the integration grid. The peaks are recomputed here from the raw
arrays, not read from ``verification``; one answer is re-simulated with scipy's Radau (an integrator
the service does not use) from the returned voltage.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp.errors import InfeasibleError
from ocp.model.params import MotorParams
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.verify import PATH_TOLERANCE
from ocp.reference.fallback_answer import analytic_fallback

TOL = 1.0 + PATH_TOLERANCE
REV = [{"kind": "hold", "duration": 0.2, "thrust": 0.4}, {"kind": "reversal", "duration": 0.3, "to": -0.4},
       {"kind": "hold", "duration": 0.2, "thrust": -0.4}]

#: (id, mission) -- the first three are the issue's own: 19.8 V / 3.6 A, 679 V / 45 A, 0.178 A answered 200
ADVERSARIAL: list[tuple[str, dict[str, Any]]] = [
    ("200-period sine 12 V 1 A", {"segments": [{"kind": "sine", "duration": 40.0, "amplitude": 0.5,
                                                "period": 0.2}], "limits": {"voltage": 12.0, "current": 1.0}}),
    ("300 reversals", {"segments": [{"kind": "sine", "duration": 15.0, "amplitude": 0.6, "period": 0.1}]}),
    ("0.05 A limit", {"segments": REV, "limits": {"current": 0.05}}),
    ("step reversals 3 V", {"segments": [*REV, {"kind": "reversal", "duration": 0.01, "to": 0.5, "shape": "step"},
                                         {"kind": "hold", "duration": 0.05, "thrust": 0.5}],
                            "limits": {"voltage": 3.0, "current": 0.3}}),
    ("no reversal above the hold limit", {"segments": [{"kind": "hold", "duration": 1.0, "thrust": 5.0}],
                                          "limits": {"voltage": 6.0}}),
    ("speed limit", {"segments": REV, "limits": {"speed": 300.0}}),
    ("continuous voltage, fast", {"segments": [{"kind": "sine", "duration": 3.0, "amplitude": 0.4, "period": 0.15}],
                                  "regularity": "continuous-voltage", "limits": {"current": 0.5}}),
    ("unmodelled friction", {"segments": REV, "limits": {"current": 0.4},
                             "params": {"J": 2.71e-5, "B": 5.31e-5, "c_tau": 2.2e-6, "c_f": 1.4e-4, "k_t": 0.0573,
                                        "k_e": 0.0573, "R": 5.0, "L": 0.002,
                                        "effects": {"coulomb_friction": {"tau_c": 0.004}}}}),
    ("torque channel", {"segments": [{"kind": "sine", "duration": 2.0, "amplitude": 0.5, "period": 0.1}],
                        "plant": "torque", "limits": {"torque": 0.005}}),
]


def _within(m: Any, res: Any) -> None:
    """Every limit holds on the output samples and on the integration grid (peaks recomputed here)."""
    lim, fine, arr = m.limits, res.fine, res.arrays
    assert fine["t"].size > arr["t"].size  # the integration grid is finer than the output
    if m.plant == "torque":
        peak = max(np.max(np.abs(fine["torque"])), np.max(np.abs(arr["torque"]))) * m.motor().J
        assert peak <= m.torque_limit() * TOL
    else:
        for ch, top in (("current", lim.current), ("voltage", lim.voltage)):
            assert max(np.max(np.abs(fine[ch])), np.max(np.abs(arr[ch]))) <= top * TOL, ch
    if lim.speed is not None:
        assert np.max(np.abs(fine["omega"])) <= lim.speed * TOL
    assert np.all(np.isfinite(arr["thrust"])) and res.verification["path_ok"]


@pytest.mark.parametrize(("name", "data"), ADVERSARIAL, ids=[n for n, _ in ADVERSARIAL])
def test_fallback_stays_within_its_limits_or_names_the_binding_one(name: str, data: dict[str, Any]) -> None:
    m = mission_from_mapping({"name": name, **data})
    try:
        res = analytic_fallback(m, "test")
    except InfeasibleError as exc:
        assert exc.field.startswith("limits"), exc
        return
    _within(m, res)
    assert res.source == "analytic-fallback"


def test_lowered_levels_are_said_and_the_shape_kept() -> None:
    """A 0.05 A limit cannot hold 0.4 N: the answer says the levels were lowered, still reverses once, and the
    held thrust is what the limit allows (the steady current sits at the limit within 5 %)."""
    m = mission_from_mapping({"segments": REV, "limits": {"current": 0.05}})
    res = analytic_fallback(m, "deadline")
    assert res.reason.startswith("deadline") and "lowered" in res.reason
    thrust = res.arrays["thrust"]
    assert np.count_nonzero(np.diff(np.sign(thrust[np.abs(thrust) > 1e-9])) != 0) == 1
    assert 0.95 * 0.05 <= np.max(np.abs(res.arrays["current"])) <= 0.05 * TOL


def test_radau_agrees_that_the_fallback_is_within_the_limits(rig: MotorParams) -> None:
    """Oracle independent of the service's RK4: the nominal DC motor (eqs. dc_mechanical, dc_electrical)
    integrated by Radau under the returned voltage stays within the 1 A / 12 V limits."""
    m = mission_from_mapping(dict(ADVERSARIAL[0][1], segments=[{"kind": "sine", "duration": 0.4, "amplitude": 0.5,
                                                                "period": 0.2}]))
    res = analytic_fallback(m, "test")
    t, v = res.arrays["command_t"], res.arrays["command"]

    def rhs(tt: float, x: np.ndarray) -> list[float]:
        w, i = x
        u = float(np.interp(tt, t, v))
        return [(rig.k_t * i - rig.B * w - rig.c_tau * w * abs(w)) / rig.J, (u - rig.R * i - rig.k_e * w) / rig.L]

    sol = solve_ivp(rhs, (t[0], t[-1]), [res.arrays["omega"][0], res.arrays["current"][0]], method="Radau",
                    max_step=5e-4, rtol=1e-7, atol=1e-9)
    assert sol.success
    assert np.max(np.abs(sol.y[1])) <= 1.0 * 1.01 and np.max(np.abs(v)) <= 12.0 * TOL
