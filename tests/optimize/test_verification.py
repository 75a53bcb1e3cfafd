"""The a-posteriori verification simulation (ocp.optimize.verify.simulate_response) against scipy's stiff solver."""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from ocp.errors import MissionError
from ocp.model.plant import DCMotorPlant
from ocp.optimize.mission import mission_from_mapping
from ocp.optimize.result import SolverProgram
from ocp.optimize.solve import optimize
from ocp.optimize.verify import sim_step, simulate_response
from tests.motor_ode import dc_motor_ode

EXAMPLE = json.loads(Path("examples/reversal.json").read_text())


def _reference(params, knots, u, x0, t_out, method="Radau"):
    """scipy's integrator restarted at every knot, tight tolerances: the oracle. Radau IIA (implicit,
    stiff-stable) by default; DOP853 (explicit, order 8) for a non-stiff winding, ten times faster there."""
    rhs, jac = dc_motor_ode(params)
    out = np.empty((len(x0), t_out.size))
    x = np.asarray(x0, float)
    for k in range(u.size):
        a, b = knots[k], knots[k + 1]
        inside = (t_out >= a) & (t_out < b)
        opts = {"rtol": 1e-11, "atol": 1e-13, "jac": jac} if method == "Radau" else {"rtol": 1e-10, "atol": 1e-12}
        sol = solve_ivp(rhs, (a, b), x, method=method, args=(float(u[k]),), t_eval=np.append(t_out[inside], b),
                        **opts)
        out[:, inside], x = sol.y[:, :-1], sol.y[:, -1]
    out[:, t_out >= knots[-1]] = x[:, None]
    return out


@pytest.mark.parametrize("inductance", [2e-3, 2e-5])
def test_verification_matches_a_stiff_solver(rig, inductance):
    """Piecewise-constant voltage, reversing the motor: RK4 on the step of ``sim_step`` agrees with Radau IIA.
    With L = 20 uH (L/R = 4 us) the former fixed 0.125 ms RK4 sub-step was outside RK4's stability interval."""
    plant = DCMotorPlant(rig.model_copy(update={"L": inductance}))
    rng = np.random.default_rng(1)
    knots = np.linspace(0.0, 0.2, 21)
    u = rng.uniform(-12.0, 12.0, 20)
    t_out = np.linspace(0.0, 0.2, 201)
    x0 = np.array([20.0, 0.1])
    sim = simulate_response(plant, knots, u, x0, t_out).at_out
    ref = _reference(plant.params, knots, u, x0, t_out)
    assert np.all(np.isfinite(sim))
    assert np.min(ref[0]) < 0 < np.max(ref[0])  # the speed reverses
    np.testing.assert_allclose(sim[0], ref[0], rtol=0, atol=1e-6 * np.max(np.abs(ref[0])))
    np.testing.assert_allclose(sim[1], ref[1], rtol=0, atol=1e-4 * np.max(np.abs(ref[1])))
    tau = inductance / rig.R
    assert sim_step(plant, x0, float(u[0])) <= 2 * 0.32 * tau * 1.01


def test_a_stiff_winding_is_optimised_and_verified(rig):
    params = {k: getattr(rig, k) for k in ("J", "B", "c_tau", "c_f", "k_t", "k_e", "R")} | {"L": 2e-5}
    r = optimize(mission_from_mapping({**EXAMPLE, "params": params}))
    assert r.source == "optimized", r.reason
    v = r.verification
    assert np.isfinite(v["thrust_rms_error"]) and v["thrust_rms_error"] < 1e-3 * 0.4
    assert v["max_abs_current"] <= 1.001 and v["max_abs_voltage"] <= 12.0 * 1.001


def test_a_winding_too_stiff_to_verify_is_a_clear_error(rig):
    plant = DCMotorPlant(rig.model_copy(update={"L": 1e-8}))
    with pytest.raises(MissionError) as err:
        simulate_response(plant, np.array([0.0, 2.0]), np.array([1.0]), np.zeros(2), np.linspace(0, 2, 3))
    assert err.value.field == "params" and "too stiff" in str(err.value)


def test_limits_are_checked_between_the_output_samples():
    """The reported peak current is the simulated response's between the 1 kHz output samples too: it matches
    an independent integration (DOP853: L/R = 0.4 ms is not stiff on 17 ms knots) of the returned command
    sampled at 20 kHz, which the output samples alone undershoot. The Radau program's answer: its held voltage
    jumps at every interval, so its current peaks between samples (the flat program's smooth voltage, held on
    short pieces, has no such transients)."""
    m = mission_from_mapping({"name": "sine", "limits": {"voltage": 12.0, "current": 1.0}, "segments": [
        {"kind": "sine", "duration": 2.0, "amplitude": 0.4, "period": 1.0, "phase": math.pi / 2}]})
    r = optimize(m, program=SolverProgram.RADAU)
    plant = DCMotorPlant(m.motor())
    knots, u = r.arrays["command_t"], r.arrays["command"][:-1]
    x0 = np.array([r.arrays["omega"][0], r.arrays["current"][0]])
    dense = np.linspace(0.0, knots[-1], 20 * (r.arrays["t"].size - 1) + 1)
    true_peak = float(np.max(np.abs(_reference(plant.params, knots, u, x0, dense, "DOP853")[1])))
    assert r.verification["max_abs_current"] == pytest.approx(true_peak, rel=2e-4)
    assert np.max(np.abs(r.arrays["current"])) < true_peak * (1 - 5e-4)  # what a 1 kHz check would miss
