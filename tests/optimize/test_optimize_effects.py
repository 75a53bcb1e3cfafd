"""The optimiser uses the calibrated plant: effects from a parameter file reach the collocation.

Oracle: the command of each answer is replayed through the *true* plant (nominal + hidden effects)
with scipy's Radau integrator; the reference optimised for the calibrated plant must be reproduced
far better than the one optimised for the nominal plant.
"""

import json
from pathlib import Path

import numpy as np
import pytest

from ocp.errors import MissionError
from ocp.model.effects import load_plant
from ocp.model.equilibrium import equilibrium, speed_for_thrust
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.solve import optimize
from ocp.simulate.open_loop import simulate

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())
RIG = {k: v for k, v in json.loads(Path("ocp/presets/paper-rig.json").read_text()).items() if k != "notes"}
HIDDEN = {"coulomb_friction": {"tau_c": 0.003}, "thrust_lag": {"tau": 0.03}}


def _true_error(result, true_plant) -> float:
    """RMS thrust error of the true plant driven by the result's exact command, vs the returned thrust."""
    ct, cv = result.arrays["command_t"], result.arrays["command"]

    def v(tt: float) -> float:
        return float(cv[min(max(int(np.searchsorted(ct, tt, side="right")) - 1, 0), cv.size - 1)])

    w0 = speed_for_thrust(true_plant, float(result.arrays["thrust"][0]), true_plant.params.c_f)
    x0, _ = equilibrium(true_plant, w0)
    t = result.arrays["t"]
    sim = simulate(true_plant, t, v, x0.tolist(), rtol=1e-8, atol=1e-9)
    return float(np.sqrt(np.mean((sim.thrust - result.arrays["thrust"]) ** 2)))


def test_calibrated_plant_is_reproduced_by_the_true_plant():
    true_plant = load_plant({**RIG, "effects": HIDDEN})
    nominal = optimize(mission_from_mapping(EXAMPLE))
    calibrated = optimize(mission_from_mapping({**EXAMPLE, "params": {**RIG, "effects": HIDDEN}}))
    assert nominal.source == calibrated.source == "optimized"
    e_nom, e_cal = _true_error(nominal, true_plant), _true_error(calibrated, true_plant)
    assert e_cal <= 1e-3 * 0.4  # the calibrated answer is what the true plant does
    assert e_cal <= 0.1 * e_nom  # the nominal answer is not
    assert calibrated.verification["max_abs_current"] <= 1.001


@pytest.mark.parametrize("effect", [{"cogging": {"tau_sin": 0.003, "tau_cos": 0.0, "periods": 2}},
                                    {"cogging": {"tau_sin": 0.003, "periods": 2, "tau_cos2": 0.0015, "tau_sin3": 1e-3}},
                                    {"input_delay": {"delay": 0.004}}, {"voltage_deadband": {"v_db": 0.4}},
                                    {"stribeck": {"tau_s": 0.004, "omega_s": 20.0, "delta": 1.0}}])
def test_stateful_and_nonsmooth_effects_solve_and_verify(effect):
    r = optimize(mission_from_mapping({**EXAMPLE, "params": {**RIG, "effects": effect}}))
    assert r.source == "optimized", r.reason
    assert _true_error(r, load_plant({**RIG, "effects": effect})) <= 2e-3 * 0.4


def test_equilibrium_holds_speed_and_thrust():
    plant = load_plant({**RIG, "effects": {**HIDDEN, "force_offset": {"f0": 0.03}}})
    w = speed_for_thrust(plant, 0.3, plant.params.c_f)
    x, u = equilibrium(plant, w)
    assert np.max(np.abs(np.array(plant.rhs(list(x), u)) * [plant.params.J, plant.params.L, 0.03])) < 1e-9
    assert float(plant.thrust(list(x))) == pytest.approx(0.3, abs=1e-9)


def test_effects_on_the_torque_channel_are_refused():
    m = mission_from_mapping({**EXAMPLE, "plant": "torque", "params": {**RIG, "effects": HIDDEN}})
    with pytest.raises(MissionError) as ei:
        optimize(m)
    assert ei.value.field == "params.effects"
